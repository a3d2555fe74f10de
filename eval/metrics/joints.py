"""Joint matching (Hungarian, scipy) and the articulation gates, batched over objects.

The joints of a whole split are held as flat rows (`JointRows`); every candidate pair of every
object is scored in one vectorised pass, the assignment is solved per object, and the matched
pairs are gated in one more pass.

Definitions (SPEC §5, with the choices the spec leaves open):
* candidate pair: same child part, or the two child parts' centroids (reference boxes) are within
  `CANDIDATE_RADIUS` nu;
* cost = axis angle + position error (+ `CHILD_PENALTY` when the children differ);
* position error = distance between the two axis lines when both joints are hinges; a slide's
  axis has no location (a translation is the same wherever its axis is drawn), so a pair with a
  slide has position error 0 in the cost, passes the origin gate and is left out of `pos_err`;
* the assignment maximises the number of candidate pairs first and minimises their total cost
  second: non-candidates cost more than all candidate costs of the object together, and any
  non-candidate pair the solver had to use is dropped afterwards;
* gates, in order: type; axis (angle > `AXIS_TOLERANCE`); origin (hinge line distance >
  `ORIGIN_TOLERANCE`); limit (after sign alignment the ranges do not overlap, or their spans
  differ by more than `HINGE_SPAN_TOLERANCE` rad / `SLIDE_SPAN_TOLERANCE` nu); else success.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

from eval.metrics.geometry import align_ranges, axis_angle, interval_iou, interval_overlap, line_distance
from jax3dc.structure.schema import Structure

CANDIDATE_RADIUS = 0.1
# Position error in the *cost* is capped: beyond 1000 object sizes every pivot is equally wrong, and
# the cap keeps the assignment's costs finite whatever finite pivot a prediction writes.
POSITION_COST_CAP = 1e3
CHILD_PENALTY = 10.0
AXIS_TOLERANCE = 0.25
ORIGIN_TOLERANCE = 0.05
HINGE_SPAN_TOLERANCE = 1.6057
SLIDE_SPAN_TOLERANCE = 0.5

GATES: tuple[str, ...] = ("type", "axis", "origin", "limit", "success")
GATE_SUCCESS = GATES.index("success")


@dataclass(frozen=True)
class JointRows:
    """All joints of one side (prediction or reference) of a batch of objects, one row each.

    Rows of object ``o`` are ``offsets[o]:offsets[o + 1]``; ``centroid`` is the child part's
    centroid from the reference boxes.
    """

    offsets: np.ndarray  # (objects + 1,) int
    child: np.ndarray  # (n,) int part id
    hinge: np.ndarray  # (n,) bool; False = slide
    axis: np.ndarray  # (n, 3)
    pivot: np.ndarray  # (n, 3)
    range: np.ndarray  # (n, 2)
    centroid: np.ndarray  # (n, 3)

    @property
    def counts(self) -> np.ndarray:
        return np.diff(self.offsets)


def joint_rows(structures: Sequence[Structure], centroids: Sequence[Mapping[int, Sequence[float]]]) -> JointRows:
    """Flatten the joints of ``structures`` (one per object) into rows; ``centroids`` per object."""
    counts, child, hinge, axis, pivot, rng, cen = [], [], [], [], [], [], []
    for s, c in zip(structures, centroids, strict=True):
        joints = s.joints()
        counts.append(len(joints))
        for part_id, j in joints.items():
            child.append(part_id)
            hinge.append(j.type == "hinge")
            axis.append(j.axis)
            pivot.append(j.pivot)
            rng.append(j.range)
            cen.append(c[part_id])
    n = len(child)
    offsets = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    return JointRows(
        offsets=offsets,
        child=np.asarray(child, dtype=np.int64),
        hinge=np.asarray(hinge, dtype=bool),
        axis=np.asarray(axis, dtype=np.float64).reshape(n, 3),
        pivot=np.asarray(pivot, dtype=np.float64).reshape(n, 3),
        range=np.asarray(rng, dtype=np.float64).reshape(n, 2),
        centroid=np.asarray(cen, dtype=np.float64).reshape(n, 3),
    )


@dataclass(frozen=True)
class CandidatePairs:
    """Every (prediction row, reference row) pair within each object, object by object.

    The pairs of object ``o`` are ``offsets[o]:offsets[o + 1]`` in row-major (pred, ref) order.
    """

    offsets: np.ndarray
    pred: np.ndarray
    ref: np.ndarray
    candidate: np.ndarray  # bool
    cost: np.ndarray


def pair_costs(pred: JointRows, ref: JointRows) -> CandidatePairs:
    """Candidate flags and matching costs for all pairs of every object, in one pass."""
    n_pred, n_ref = pred.counts, ref.counts
    sizes = n_pred * n_ref
    offsets = np.zeros(len(sizes) + 1, dtype=np.int64)
    np.cumsum(sizes, out=offsets[1:])
    obj = np.repeat(np.arange(len(sizes)), sizes)
    local = np.arange(offsets[-1]) - offsets[obj]
    width = n_ref[obj]
    pi = pred.offsets[obj] + local // np.maximum(width, 1)
    ri = ref.offsets[obj] + local % np.maximum(width, 1)

    same_child = pred.child[pi] == ref.child[ri]
    near = np.linalg.norm(pred.centroid[pi] - ref.centroid[ri], axis=1) <= CANDIDATE_RADIUS
    both_hinge = pred.hinge[pi] & ref.hinge[ri]
    position = np.where(
        both_hinge, line_distance(pred.pivot[pi], pred.axis[pi], ref.pivot[ri], ref.axis[ri]), 0.0
    )
    position = np.minimum(position, POSITION_COST_CAP)
    cost = axis_angle(pred.axis[pi], ref.axis[ri]) + position + np.where(same_child, 0.0, CHILD_PENALTY)
    return CandidatePairs(offsets, pi, ri, same_child | near, cost)


@dataclass(frozen=True)
class Matches:
    """Matched joint pairs: global row indices into the prediction and reference `JointRows`."""

    obj: np.ndarray
    pred: np.ndarray
    ref: np.ndarray


def match_joints(pred: JointRows, ref: JointRows) -> Matches:
    """Hungarian matching of predicted to reference joints inside each object."""
    pairs = pair_costs(pred, ref)
    n_ref = ref.counts
    objs, pis, ris = [], [], []
    for o in np.flatnonzero(np.diff(pairs.offsets)):
        lo, hi = pairs.offsets[o], pairs.offsets[o + 1]
        cand = pairs.candidate[lo:hi]
        if not cand.any():
            continue
        cost = pairs.cost[lo:hi]
        if hi - lo == 1:
            rows, cols = np.zeros(1, np.int64), np.zeros(1, np.int64)
        else:
            # More than every candidate pair of this object together: fewer non-candidates wins.
            big = 1.0 + 2.0 * float(np.abs(cost[cand]).sum())
            block = np.where(cand, cost, big).reshape(-1, n_ref[o])
            rows, cols = linear_sum_assignment(block)
        keep = cand.reshape(-1, n_ref[o])[rows, cols]
        objs.append(np.full(int(keep.sum()), o))
        pis.append(pred.offsets[o] + rows[keep])
        ris.append(ref.offsets[o] + cols[keep])
    if not objs:
        empty = np.zeros(0, dtype=np.int64)
        return Matches(empty, empty, empty)
    return Matches(np.concatenate(objs), np.concatenate(pis), np.concatenate(ris))


@dataclass(frozen=True)
class MatchedJoints:
    """Per matched pair: the measures and the first failed gate (index into GATES)."""

    obj: np.ndarray
    pred_child: np.ndarray
    ref_child: np.ndarray
    type_ok: np.ndarray  # bool
    angle: np.ndarray  # rad
    line_distance: np.ndarray  # nu; NaN unless both are hinges
    range_iou: np.ndarray  # NaN unless the types agree
    gate: np.ndarray  # int


def gate_matches(pred: JointRows, ref: JointRows, m: Matches) -> MatchedJoints:
    """Measure every matched pair and assign it to its first failed gate."""
    p, r = m.pred, m.ref
    type_ok = pred.hinge[p] == ref.hinge[r]
    angle = axis_angle(pred.axis[p], ref.axis[r])
    both_hinge = pred.hinge[p] & ref.hinge[r]
    dist = np.where(both_hinge, line_distance(pred.pivot[p], pred.axis[p], ref.pivot[r], ref.axis[r]), np.nan)
    aligned = align_ranges(pred.axis[p], pred.range[p], ref.axis[r])
    iou = np.where(type_ok, interval_iou(aligned, ref.range[r]), np.nan)

    span_diff = np.abs((aligned[:, 1] - aligned[:, 0]) - (ref.range[r, 1] - ref.range[r, 0]))
    span_tol = np.where(ref.hinge[r], HINGE_SPAN_TOLERANCE, SLIDE_SPAN_TOLERANCE)
    checks = np.stack([
        type_ok,
        angle <= AXIS_TOLERANCE,
        ~both_hinge | (dist <= ORIGIN_TOLERANCE),
        (interval_overlap(aligned, ref.range[r]) > 0) & (span_diff <= span_tol),
    ])
    failed = ~checks
    gate = np.where(failed.any(axis=0), failed.argmax(axis=0), GATE_SUCCESS)
    return MatchedJoints(m.obj, pred.child[p], ref.child[r], type_ok, angle, dist, iou, gate)
