"""Scores of stage-1 factory parameters (jax3dc.parameters) against each record's own.

Both texts run through the factory (``run_parameters``: the prediction as parsed, never
evaluated); a prediction that does not parse or fit its schema scores zero everywhere but
``runs``. Per object:

* ``runs``: the text parses, fits its category's schema and runs into parts;
* ``category``: the predicted category is the reference's;
* ``count_exact``: as many parts as the reference (eval.metrics.part_matching);
* ``matched_iou``: box IoU of parts matched one-to-one by overlap, whatever their ids;
* ``ids``, ``box_iou``: the per-id scores of the code task (eval.metrics.programs), which stage 2
  sees as is;
* ``chamfer``: symmetric Chamfer distance (nu) between the whole objects' surfaces.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from eval.metrics.part_matching import matched_iou
from eval.metrics.programs import surface_points, box_iou, chamfer
from jax3dc.errors import Jax3dcError
from jax3dc.parameters import Parameters, Schema, parse_parameters


@dataclass(frozen=True)
class ParametersScore:
    key: str
    runs: bool
    category: bool
    count_exact: bool
    count_err: int
    matched_iou: float
    ids: bool
    box_iou: float
    chamfer: float | None  # None when the prediction does not run
    error: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


Runner = Callable[[Parameters], Any]  # parameters -> an object with .parts (jax3dc.factories.run_parameters)


def score_parameters(key: str, reference: str, predicted: str, schemas: Mapping[str, Schema],
                     run: Runner) -> ParametersScore:
    """One object's scores; ``reference`` must run (it is the record's own text)."""
    ref_params = parse_parameters(reference, schemas)
    ref = run(ref_params).parts
    try:
        pred_params = parse_parameters(predicted, schemas)
        pred = run(pred_params).parts
    except Jax3dcError as e:
        return ParametersScore(key, False, False, False, len(ref), 0.0, False, 0.0, None, str(e))
    ious = [box_iou(np.asarray(m.bounds), np.asarray(pred[pid].bounds)) if pid in pred else 0.0
            for pid, m in ref.items()]
    return ParametersScore(key, True, pred_params.category == ref_params.category, len(pred) == len(ref),
                           abs(len(pred) - len(ref)), matched_iou(ref, pred), set(pred) == set(ref),
                           float(np.mean(ious)), chamfer(surface_points(ref), surface_points(pred)))


def summarise(scores: Sequence[ParametersScore]) -> dict[str, Any]:
    """Table row: percentages over every object (a failed text counting 0), Chamfer over those that run."""
    n = len(scores)
    ran = [s for s in scores if s.runs]

    def pct(values) -> float | None:
        return 100.0 * float(np.mean(list(values))) if n else None

    return {
        "objects": n,
        "runs": pct(s.runs for s in scores),
        "category": pct(s.category for s in scores),
        "count_exact": pct(s.count_exact for s in scores),
        "count_err": float(np.mean([s.count_err for s in scores])) if n else None,
        "matched_iou": pct(s.matched_iou for s in scores),
        "ids": pct(s.ids for s in scores),
        "box_iou": pct(s.box_iou for s in scores),
        "chamfer": float(np.mean([s.chamfer for s in ran])) if ran else None,
    }
