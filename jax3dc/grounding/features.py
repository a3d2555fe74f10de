"""What the part boxes say about a joint: the numbers the joint prior reads.

Everything here is computed from the legend boxes a prompt states (SPEC §3) and the parent map of
the structure being grounded, so the same features exist in training (a record's target), in
``eval run`` and in ``predict``. A box side is floored at ``MIN_SIDE`` so a flat or degenerate box
gives finite numbers.

Two feature sets:

* ``joint_features``: one vector per moving part, read by the type-and-axis classifier — the
  child's shape (sides, their ratios, which side is thin), its size and place relative to its
  parent's box (how far it is sunk in or sticks out of each face), its absolute place, and whether
  it carries children (a handle).
* ``line_features``: one vector per candidate hinge line — the nine lines of the child's box along
  the axis (four edges, four face centre lines, the centre line; ``LINE_GRID``) — read by the
  hinge-line scorer: is the line on an edge, does it touch the parent's box, is it on the side
  towards the parent's centre, away from a handle, at the top or the back.
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import product

import numpy as np

from jax3dc.structure.schema import Box

MIN_SIDE = 1e-3  # nu: the smallest box side a ratio or logarithm is taken of
THIN_SIDE = 0.05  # nu: a side this thin puts every line of that direction within the origin tolerance
LINE_GRID = (-0.5, 0.0, 0.5)  # box-side fractions of the candidate hinge lines in each cross direction
LINES: tuple[tuple[float, float], ...] = tuple(product(LINE_GRID, LINE_GRID))
JOINT_FEATURES = 29
LINE_FEATURES = 16


def _sides(box: Box) -> np.ndarray:
    return np.maximum(np.asarray(box.extent, float), MIN_SIDE)


def cross_dims(k: int) -> tuple[int, int]:
    """The two directions across an axis along direction ``k``."""
    i, j = (d for d in range(3) if d != k)
    return i, j


def joint_features(child: Box, parent: Box | None, handles: Sequence[Box] = ()) -> np.ndarray:
    """The classifier's input for a part moving relative to ``parent`` (None: the unit box at the
    origin stands in, as for a part written without a parent)."""
    e, c = _sides(child), np.asarray(child.centroid, float)
    if parent is None:
        big, mid = np.ones(3), np.zeros(3)
    else:
        big, mid = _sides(parent), np.asarray(parent.centroid, float)
    thin = np.zeros(3)
    thin[int(np.argmin(e))] = 1.0
    place = (c - mid) / (big / 2)
    sunk_low = ((c - e / 2) - (mid - big / 2)) / big  # < 0: sticks out of the parent's low face
    sunk_high = ((mid + big / 2) - (c + e / 2)) / big
    return np.concatenate([
        e, np.log(e / e.max()), thin, np.log(e / big), place, np.abs(place), sunk_low, sunk_high,
        [np.log(np.prod(e) / np.prod(big))], c, [min(len(handles), 3)],
    ])


def line_features(child: Box, parent: Box | None, k: int, handles: Sequence[Box] = ()) -> np.ndarray:
    """(9, LINE_FEATURES): one row per line of ``LINES`` of the child's box along direction ``k``."""
    e, c = _sides(child), np.asarray(child.centroid, float)
    i, j = cross_dims(k)
    mid = c if parent is None else np.asarray(parent.centroid, float)
    big = e if parent is None else _sides(parent)
    handle = np.mean([np.asarray(h.centroid, float) for h in handles], axis=0) if handles else c
    rows = []
    for gi, gj in LINES:
        row = []
        for d, g in ((i, gi), (j, gj)):
            at = c[d] + g * e[d]  # the line's coordinate in direction d
            to_parent_face = min(abs(at - (mid[d] - big[d] / 2)), abs(at - (mid[d] + big[d] / 2)))
            row += [
                abs(g) > 0,  # on an edge of this direction
                (abs(g) > 0) * (e[d] < THIN_SIDE),  # ... of a thin side (carries no information)
                np.sign(g) * np.sign(round(mid[d] - c[d], 3)),  # towards the parent's centre
                np.sign(g) * np.sign(round(handle[d] - c[d], 3)),  # towards the handle
                np.sign(g) * (d == 2),  # top (+) or bottom (-)
                np.sign(g) * (d == 1),  # back (+) or front (-)
                np.exp(-to_parent_face / 0.05),  # on a face plane of the parent's box
            ]
        row += [gi == 0 and gj == 0, (abs(gi) > 0) and (abs(gj) > 0)]  # centre line; a corner edge
        rows.append(row)
    return np.asarray(rows, float)
