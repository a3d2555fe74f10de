"""The joint prior: two small linear models fitted on real objects' part boxes (``train.joint_prior``).

* the type-and-axis classifier: softmax over ``CLASSES`` (hinge or slide, along x, y or z) of a
  linear function of the standardised ``joint_features``;
* the hinge-line scorer: a conditional logit over the nine candidate lines, a linear function of
  each line's ``line_features``.

The weights ship as ``joint_prior.json`` beside this module (a few hundred numbers), with the data
they were fitted on and the two decision constants the grounding uses: ``keep_ratio`` (how much
likelier the geometry must find another type or axis than the one the model wrote before the model
is overruled) and ``line_sigma`` (nu: how close a candidate line must lie to the model's own hinge
line for that to count).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from jax3dc.errors import InputFileError
from jax3dc.grounding.features import JOINT_FEATURES, LINE_FEATURES

CLASSES: tuple[tuple[str, int], ...] = tuple((t, k) for t in ("hinge", "slide") for k in range(3))
PRIOR_FILE = Path(__file__).with_name("joint_prior.json")


@dataclass(frozen=True)
class JointPrior:
    """Weights of the two models and the grounding's decision constants (module docstring)."""

    mean: np.ndarray  # (JOINT_FEATURES,) standardisation of joint_features
    scale: np.ndarray  # (JOINT_FEATURES,)
    class_weights: np.ndarray  # (JOINT_FEATURES + 1, len(CLASSES)); the last row is the bias
    line_weights: np.ndarray  # (LINE_FEATURES,)
    keep_ratio: float = 4.0
    line_sigma: float = 0.05
    note: str = ""

    def __post_init__(self):
        shapes = {"mean": (JOINT_FEATURES,), "scale": (JOINT_FEATURES,),
                  "class_weights": (JOINT_FEATURES + 1, len(CLASSES)), "line_weights": (LINE_FEATURES,)}
        for name, shape in shapes.items():
            value = getattr(self, name)
            if value.shape != shape or not np.all(np.isfinite(value)):
                raise ValueError(f"joint prior {name}: expected finite values of shape {shape}, got {value.shape}")
        if not np.all(self.scale > 0):
            raise ValueError("joint prior scale: every entry must be positive")
        if not (self.keep_ratio >= 1 and self.line_sigma > 0):
            raise ValueError(f"joint prior: keep_ratio >= 1 and line_sigma > 0 required, got "
                             f"{self.keep_ratio}, {self.line_sigma}")

    def class_logprobs(self, features: np.ndarray) -> np.ndarray:
        """log P(class | features) over ``CLASSES``."""
        z = np.append((features - self.mean) / self.scale, 1.0)
        logits = z @ self.class_weights
        logits = logits - logits.max()
        return logits - math.log(float(np.exp(logits).sum()))

    def line_logits(self, features: np.ndarray) -> np.ndarray:
        """Unnormalised log-scores of the nine candidate lines (rows of ``features``)."""
        return features @ self.line_weights

    def to_dict(self) -> dict:
        return {"mean": self.mean.tolist(), "scale": self.scale.tolist(),
                "class_weights": self.class_weights.tolist(), "line_weights": self.line_weights.tolist(),
                "keep_ratio": self.keep_ratio, "line_sigma": self.line_sigma, "note": self.note}

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="utf-8")

    @classmethod
    def load(cls, path: str | Path = PRIOR_FILE) -> "JointPrior":
        path = Path(path)
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
            return cls(np.asarray(doc["mean"], float), np.asarray(doc["scale"], float),
                       np.asarray(doc["class_weights"], float), np.asarray(doc["line_weights"], float),
                       float(doc["keep_ratio"]), float(doc["line_sigma"]), str(doc.get("note", "")))
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise InputFileError(path, f"not a valid joint prior file: {e}") from None


@lru_cache(maxsize=1)
def shipped_prior() -> JointPrior:
    """The packaged prior, read once per process."""
    return JointPrior.load(PRIOR_FILE)
