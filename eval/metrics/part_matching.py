"""Parts matched one-to-one by box overlap, whatever their ids (issue 49's fair stage-1 scores).

Stage 2 reads parts by id, so the per-id scores (eval.metrics.programs) say whether a stage-1
output is usable as is; but a right part under another id, or one part early in the order, scores
zero there. Here every reference part is paired with at most one predicted part so that the
summed 3-D box IoU is largest (Hungarian, scipy), and

* ``matched_iou``: that sum over max(reference parts, predicted parts), so a part without a
  partner on either side counts 0 (a prediction cannot gain by writing more parts);
* ``count_exact``: the prediction has as many parts as the reference.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import trimesh
from scipy.optimize import linear_sum_assignment

from eval.metrics.programs import box_iou
from jax3dc.structure import Box


Bounds = Mapping[int, np.ndarray]
"""Part id -> its axis-aligned box as [[lo xyz], [hi xyz]] (nu)."""


def _mesh_bounds(parts: Mapping[int, trimesh.Trimesh]) -> dict[int, np.ndarray]:
    """The box of each part mesh."""
    return {pid: np.asarray(parts[pid].bounds, dtype=np.float64) for pid in parts}


def box_bounds(boxes: Mapping[int, Box]) -> dict[int, np.ndarray]:
    """The box of each centroid-and-extent Box (a record's meta boxes, a legend's)."""
    return {pid: np.asarray([np.subtract(b.centroid, np.divide(b.extent, 2)),
                             np.add(b.centroid, np.divide(b.extent, 2))], dtype=np.float64)
            for pid, b in boxes.items()}


def match_bounds(reference: Bounds, predicted: Bounds) -> list[tuple[int, int, float]]:
    """(reference id, predicted id, box IoU) of the one-to-one pairing with the largest summed
    IoU; pairs that do not overlap at all are left out."""
    if not reference or not predicted:
        return []
    ref_ids, pred_ids = sorted(reference), sorted(predicted)
    iou = np.asarray([[box_iou(reference[r], predicted[p]) for p in pred_ids] for r in ref_ids])
    rows, cols = linear_sum_assignment(iou, maximize=True)
    return [(ref_ids[r], pred_ids[c], float(iou[r, c])) for r, c in zip(rows, cols) if iou[r, c] > 0]


def match_parts(reference: Mapping[int, trimesh.Trimesh],
                predicted: Mapping[int, trimesh.Trimesh]) -> list[tuple[int, int, float]]:
    """``match_bounds`` of two sets of part meshes."""
    return match_bounds(_mesh_bounds(reference), _mesh_bounds(predicted))


def matched_iou(reference: Mapping[int, trimesh.Trimesh], predicted: Mapping[int, trimesh.Trimesh]) -> float:
    """Summed IoU of the matched pairs over the larger part count (0 when either side is empty)."""
    n = max(len(reference), len(predicted))
    return sum(iou for _, _, iou in match_parts(reference, predicted)) / n if n else 0.0
