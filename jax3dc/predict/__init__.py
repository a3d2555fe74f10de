"""`jax3dc predict`: image in, articulated simulation-ready object out (see ``pipeline``).

``predict`` and ``PredictResult`` are imported on first use, so that registering the CLI command
(every `jax3dc` run does) does not pay for importing jax, MuJoCo and the exporters.
"""

__all__ = ["PredictResult", "predict"]


def __getattr__(name: str):
    if name in __all__:
        from jax3dc.predict import pipeline

        return getattr(pipeline, name)
    raise AttributeError(f"module 'jax3dc.predict' has no attribute {name!r}")
