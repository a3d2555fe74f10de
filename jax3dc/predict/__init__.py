"""`jax3dc predict`: image in, articulated simulation-ready object out (see ``pipeline``).

``predict``, its ``PredictConfig`` and ``PredictResult`` are imported on first use, so that
registering the CLI command (every `jax3dc` run does) does not pay for importing jax, MuJoCo and
the exporters (1.7 s of imports for jax alone, measured with ``python -X importtime -c "import
jax3dc.cli"``).
"""

__all__ = ["PredictConfig", "PredictResult", "predict"]


def __getattr__(name: str):
    if name in __all__:
        from jax3dc.predict import pipeline  # lazy: see above (1.7 s alone, 0.25 s after `jax3dc --help`)

        return getattr(pipeline, name)
    raise AttributeError(f"module 'jax3dc.predict' has no attribute {name!r}")
