"""Stage 1's parts scored as boxes, whatever made them (issue 64): RS-dgIoU, parts matched, extra
parts, part-kind accuracy.

A part is an axis-aligned box [[lo xyz], [hi xyz]] in the normalised frame at rest, with a kind
(``jax3dc.stage1_slots.kinds``) or None where the reference names none.

**RS-dgIoU** (SINGAPO's resting-state generalised-IoU distance, from the description of its
``metrics/iou_cdist.py``, computed here exactly for axis-aligned boxes instead of by sampling):
predicted and reference parts are paired one-to-one by the Hungarian algorithm on box distance, the
mean Euclidean distance between the two boxes' eight corresponding corners; a pair's distance is
1 - gIoU (gIoU: IoU minus the share of the smallest enclosing box that neither box fills, in
[-1, 1], so the distance is in [0, 2]); a part left without a partner, on either side, counts the
largest distance, 2 (gIoU -1). The score is symmetric, the mean of the predicted side's average and
the reference side's average:

    RS-dgIoU = ( (Σ_pairs d + 2·(P − M)) / P  +  (Σ_pairs d + 2·(R − M)) / R ) / 2

with P predicted parts, R reference parts, M = min(P, R) pairs. An empty prediction scores 2 (0 when
the reference is empty too). Lower is better; SINGAPO reports about 0.76-0.83 on its
PartNet-Mobility split, URDFormer about 1.07.

**Matched / extra / kind accuracy**: the pairing that maximises summed box IoU
(``eval.metrics.part_matching.match_bounds``, as ``eval.pixels`` pairs parts); a pair counts as
matched when its IoU is at least MATCH_IOU; extra parts are the predicted parts not matched. Kind
accuracy is the share of matched pairs, among those whose reference names a kind, where the
predicted kind is the reference's.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from eval.metrics.part_matching import match_bounds

MATCH_IOU = 0.5
UNMATCHED_DISTANCE = 2.0  # 1 - gIoU of a part without a partner (gIoU -1)

_CORNERS = np.array([[(i >> k) & 1 for k in range(3)] for i in range(8)], np.float64)  # [8, 3] of 0 / 1


def giou_3d(a: np.ndarray, b: np.ndarray) -> float:
    """Generalised IoU of two axis-aligned boxes [[lo xyz], [hi xyz]]; see the module docstring."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    inter = np.clip(np.minimum(a[1], b[1]) - np.maximum(a[0], b[0]), 0.0, None).prod()
    union = np.prod(a[1] - a[0]) + np.prod(b[1] - b[0]) - inter
    enclosing = np.prod(np.maximum(a[1], b[1]) - np.minimum(a[0], b[0]))
    if enclosing <= 0:  # both boxes are the same point (or flat in one shared plane)
        return 1.0 if np.allclose(a, b) else -1.0
    iou = inter / union if union > 0 else 0.0
    return float(iou - (enclosing - union) / enclosing)


def corner_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Mean distance between the eight corresponding corners of two boxes (the pairing's cost)."""
    ca = a[0] + _CORNERS * (a[1] - a[0])
    cb = b[0] + _CORNERS * (b[1] - b[0])
    return float(np.linalg.norm(ca - cb, axis=-1).mean())


def rs_dgiou(reference: Sequence[np.ndarray], predicted: Sequence[np.ndarray]) -> float:
    """RS-dgIoU of two lists of boxes; see the module docstring."""
    r, p = len(reference), len(predicted)
    if r == 0 and p == 0:
        return 0.0
    if r == 0 or p == 0:
        return UNMATCHED_DISTANCE
    cost = np.asarray([[corner_distance(np.asarray(a), np.asarray(b)) for b in predicted] for a in reference])
    rows, cols = linear_sum_assignment(cost)
    paired = sum(1.0 - giou_3d(reference[i], predicted[j]) for i, j in zip(rows, cols))
    m = len(rows)
    return 0.5 * ((paired + UNMATCHED_DISTANCE * (p - m)) / p + (paired + UNMATCHED_DISTANCE * (r - m)) / r)


@dataclass(frozen=True)
class PartBoxScore:
    """One object's part scores (see the module docstring)."""

    key: str
    dgiou: float
    reference: int
    predicted: int
    matched: int
    extra: int
    kinds_scored: int  # matched pairs whose reference names a kind
    kinds_right: int

    def to_dict(self) -> dict:
        return asdict(self)


def score_part_boxes(key: str, reference: Sequence[np.ndarray], reference_kinds: Sequence[str | None],
                     predicted: Sequence[np.ndarray], predicted_kinds: Sequence[str]) -> PartBoxScore:
    """The scores of one object's predicted parts against its reference parts (boxes, kinds)."""
    pairs = match_bounds(dict(enumerate(np.asarray(b, np.float64) for b in reference)),
                         dict(enumerate(np.asarray(b, np.float64) for b in predicted)))
    matched = [(i, j) for i, j, iou in pairs if iou >= MATCH_IOU]
    named = [(i, j) for i, j in matched if reference_kinds[i] is not None]
    right = sum(reference_kinds[i] == predicted_kinds[j] for i, j in named)
    return PartBoxScore(key, rs_dgiou(reference, predicted), len(reference), len(predicted), len(matched),
                        len(predicted) - len(matched), len(named), right)


def summarise(scores: Sequence[PartBoxScore]) -> dict[str, float | int]:
    """Over objects: mean RS-dgIoU, the share of reference parts matched, the share of predicted
    parts that are extra, and kind accuracy over matched pairs with a reference kind beside the
    counts it is made of (an accuracy of 0.0 over no pair is no measurement)."""
    total = lambda field: sum(getattr(s, field) for s in scores)
    share = lambda a, b: round(a / b, 4) if b else 0.0
    return {"objects": len(scores), "rs_dgiou": round(float(np.mean([s.dgiou for s in scores])), 4) if scores else 0.0,
            "reference_parts": total("reference"), "predicted_parts": total("predicted"),
            "matched": total("matched"), "matched_share": share(total("matched"), total("reference")),
            "extra": total("extra"), "extra_share": share(total("extra"), total("predicted")),
            "kinds_scored": total("kinds_scored"), "kinds_right": total("kinds_right"),
            "kind_accuracy": share(total("kinds_right"), total("kinds_scored"))}
