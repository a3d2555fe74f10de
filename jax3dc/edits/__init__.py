"""Edits by hand (SPEC §9): a small JSON patch on a predicted structure (``patch``), the named axes
and hinge lines it picks from (``lines``), and its application to a `jax3dc predict` folder, which
re-runs the physics check and rewrites every export through predict's own writers (``folder``,
``staging``). `jax3dc edit` (``cli``) and the local app apply edits through ``folder.edit_folder``.
"""
