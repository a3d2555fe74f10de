"""Scores of stage-1 part programs (SPEC §6) against each record's own program.

Both programs run in the interpreter (parsed, never exec-ed, under its budget); a prediction
that does not parse or run scores zero everywhere but ``runs``. Per object:

* ``runs``: the program parses and runs into at least one part;
* ``ids``: its part ids are exactly the reference's (stage 2 reads parts by these ids);
* ``count_err``: |predicted parts - reference parts|;
* ``box_iou``: mean over the reference parts of the 3-D IoU of the axis-aligned bounds of the
  part with the same id (a missing part scores 0), the part layout stage 2 sees in S;
* ``chamfer``: symmetric Chamfer distance (nu, mean of both directions) between surface samples
  of the whole objects, the shape itself (only for programs that run).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Mapping, Sequence

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from jax3dc.errors import Jax3dcError
from jax3dc.program.interpreter import run_program

SURFACE_SAMPLES = 4000  # points per object for the Chamfer distance


@dataclass(frozen=True)
class ProgramScore:
    key: str
    runs: bool
    ids: bool
    count_err: int
    box_iou: float
    chamfer: float | None  # None when the prediction does not run
    error: str | None = None  # the interpreter's message for a prediction that does not run

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def box_iou(a: np.ndarray, b: np.ndarray) -> float:
    """IoU of two axis-aligned boxes given as [[lo xyz], [hi xyz]] (a flat box has volume 0)."""
    overlap = np.clip(np.minimum(a[1], b[1]) - np.maximum(a[0], b[0]), 0.0, None).prod()
    union = np.prod(a[1] - a[0]) + np.prod(b[1] - b[0]) - overlap
    return float(overlap / union) if union > 0 else float(np.allclose(a, b))


def chamfer(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric Chamfer distance between point sets: mean nearest distance a->b and b->a, halved."""
    return float((cKDTree(b).query(a)[0].mean() + cKDTree(a).query(b)[0].mean()) / 2)


def surface_points(parts: Mapping[int, trimesh.Trimesh]) -> np.ndarray:
    whole = trimesh.util.concatenate([m for m in parts.values() if len(m.faces)])
    return np.asarray(whole.sample(SURFACE_SAMPLES, seed=0), dtype=np.float64)


def score_program(key: str, reference: str, predicted: str) -> ProgramScore:
    """One object's scores; ``reference`` must run (it is the record's own program)."""
    ref = run_program(reference).parts
    try:
        pred = run_program(predicted).parts
    except Jax3dcError as e:
        return ProgramScore(key, False, False, len(ref), 0.0, None, str(e))
    ious = [box_iou(np.asarray(m.bounds), np.asarray(pred[pid].bounds)) if pid in pred else 0.0
            for pid, m in ref.items()]
    return ProgramScore(key, True, set(pred) == set(ref), abs(len(pred) - len(ref)), float(np.mean(ious)),
                        chamfer(surface_points(ref), surface_points(pred)))


def summarise(scores: Sequence[ProgramScore]) -> dict[str, Any]:
    """Table row: percentages of objects that run / have the right ids, means of the rest (box IoU
    over every object, a failed program counting 0; Chamfer over the programs that run)."""
    n = len(scores)
    ran = [s for s in scores if s.runs]
    return {
        "objects": n,
        "runs": 100.0 * len(ran) / n if n else None,
        "ids": 100.0 * sum(s.ids for s in scores) / n if n else None,
        "count_err": float(np.mean([s.count_err for s in scores])) if n else None,
        "box_iou": 100.0 * float(np.mean([s.box_iou for s in scores])) if n else None,
        "chamfer": float(np.mean([s.chamfer for s in ran])) if ran else None,
    }
