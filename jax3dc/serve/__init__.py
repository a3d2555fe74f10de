"""`jax3dc serve`: a local app where a person drops photos, each is predicted in turn with the
models loaded once (``jobs``), and a joint is fixed by hand in a form that applies the same edit
as `jax3dc edit` (``app``); uploads are streamed to disk under a size cap and checked as
``predict`` reads images (``uploads``). `jax3dc view DIR --serve` serves one predict folder with
the same page (``cli.serve_folder``).
"""
