"""`jax3dc predict`: image in, articulated simulation-ready object out (see ``pipeline``)."""

from eval.predict.pipeline import PredictResult, predict

__all__ = ["PredictResult", "predict"]
