"""Joint geometry compared pairwise, vectorised over rows: axis angle, axis-line distance, ranges.

Every function takes arrays whose leading dimension is the pair (row) index, so one call scores
all candidate or matched joint pairs of a whole split at once.
"""

from __future__ import annotations

import numpy as np

# Below this |a1 x a2| (sine of the angle between unit axes) the skew-line formula divides by a
# number too small to trust, so the lines are treated as parallel.
PARALLEL_SINE = 1e-6


def unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` scaled to unit length (rows of zeros stay zero)."""
    v = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, n, out=np.zeros_like(v), where=n > 0)


def axis_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sign-invariant angle (radians, in [0, pi/2]) between axis rows ``a`` and ``b``.

    An axis and its negation describe the same joint line, so the angle is taken between lines:
    atan2(|a x b|, |a . b|), which stays accurate near 0 where arccos does not.
    """
    a, b = unit(a), unit(b)
    sine = np.linalg.norm(np.cross(a, b), axis=-1)
    cosine = np.abs(np.einsum("ij,ij->i", a, b))
    return np.arctan2(sine, cosine)


def line_distance(p1: np.ndarray, a1: np.ndarray, p2: np.ndarray, a2: np.ndarray) -> np.ndarray:
    """Distance between the infinite lines {p1 + t a1} and {p2 + t a2}, row by row.

    Skew lines: |(p2 - p1) . (a1 x a2)| / |a1 x a2|. When the axes are parallel (or nearly, see
    PARALLEL_SINE) that quotient is 0/0, and the distance is the offset of p1 - p2 perpendicular
    to the common direction, ||(p1 - p2) x a_hat|| with a_hat = a2 (the reference axis when p2, a2
    is the reference) -- never the component along an arbitrary perpendicular.

    This is the distance of the infinite lines: two axes a little apart in angle meet somewhere,
    possibly far outside the object, so a tilted axis can score a small distance however far it
    sits from the reference inside the object. The axis gate (0.25 rad) is checked first.
    """
    a1, a2 = unit(a1), unit(a2)
    d = np.asarray(p2, dtype=np.float64) - np.asarray(p1, dtype=np.float64)
    # Work on d / scale so that squaring inside the norm cannot overflow for absurd pivots.
    scale = np.maximum(np.abs(d).max(axis=-1, initial=0.0), 1.0)
    d = d / scale[:, None]
    normal = np.cross(a1, a2)
    sine = np.linalg.norm(normal, axis=-1)
    parallel = sine < PARALLEL_SINE
    skew = np.abs(np.einsum("ij,ij->i", d, normal)) / np.where(parallel, 1.0, sine)
    offset = np.linalg.norm(np.cross(d, a2), axis=-1)
    return scale * np.where(parallel, offset, skew)


def align_ranges(pred_axis: np.ndarray, pred_range: np.ndarray, ref_axis: np.ndarray) -> np.ndarray:
    """Predicted ranges expressed along the reference axis direction.

    Where the predicted axis points against the reference one (negative dot product) the same
    motion reads [-hi, -lo]; elsewhere the range is unchanged.
    """
    pred_range = np.asarray(pred_range, dtype=np.float64)
    against = np.einsum("ij,ij->i", np.asarray(pred_axis, float), np.asarray(ref_axis, float)) < 0
    flipped = -pred_range[:, ::-1]
    return np.where(against[:, None], flipped, pred_range)


def interval_overlap(r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """Length of the intersection of intervals [lo, hi] row by row (0 when disjoint)."""
    return np.maximum(0.0, np.minimum(r1[:, 1], r2[:, 1]) - np.maximum(r1[:, 0], r2[:, 0]))


def interval_iou(r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """Intersection over union of intervals row by row.

    Two identical zero-length intervals have IoU 1; a zero-length interval against anything else
    has IoU 0.
    """
    r1 = np.asarray(r1, dtype=np.float64)
    r2 = np.asarray(r2, dtype=np.float64)
    inter = interval_overlap(r1, r2)
    union = (r1[:, 1] - r1[:, 0]) + (r2[:, 1] - r2[:, 0]) - inter
    same = np.all(r1 == r2, axis=1)
    iou = np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)
    return np.where((union <= 0) & same, 1.0, iou)
