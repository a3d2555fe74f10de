"""Structure predictions that need no training, computed from the part boxes alone.

* ``star``: the largest part (by box volume; ties: smallest id) is the root and every other part is
  a rigid child of it -- what a model that knows nothing but the part list would write.
* ``heuristic``: a tree from containment and adjacency of boxes, joints guessed from box shape
  and position, and relations from matching box sizes (rules below).
* ``reference``: the reference itself, a sanity row that must score perfectly.

Heuristic rules (normalised frame: +Z up, front facing -Y; tolerances in nu):
1. Parts are ranked by volume, largest first (ties: smallest id). A part's parent is chosen among
   higher-ranked parts, so the result is always a forest: the smallest box that contains it
   (within CONTAIN_TOL); else, of the parts it touches (gap <= TOUCH_TOL), the nearest (gap to
   1e-3 nu), then the one with the largest contact area; else it starts an object of its own (a
   root), which is how separate objects of a scene arise.
2. A thin flat part (Y extent <= THIN_RATIO x its X and Z extents) whose Y span reaches its
   parent's front plane (within FRONT_TOL) is a door: a hinge about +Z on its vertical edge
   nearer the parent's matching side wall, at the door's back face, opening outwards (towards
   -Y) by up to 90 degrees.
3. A box-like part (smallest extent >= THIN_RATIO x its largest) contained in its parent and
   reaching the parent's front plane is a drawer: a slide along -Y, out by 0.8 of its depth.
4. Siblings with the same sorted extents (within SIZE_TOL) are `symmetric` when their centroids
   mirror across a principal plane through the parent's centroid (within MIRROR_TOL), otherwise
   `instance`.
"""

from __future__ import annotations

import itertools
import math
from typing import Iterable, Mapping

import numpy as np

from jax3dc.structure.schema import Box, Joint, Material, Node, Relation, Structure

CONTAIN_TOL = 0.02
TOUCH_TOL = 0.02
THIN_RATIO = 0.25
FRONT_TOL = 0.05
SLIDE_FRACTION = 0.8
SIZE_TOL = 0.01
MIRROR_TOL = 0.02

_MATERIALS = {0: Material("Other", "unknown")}
# plane name -> index of the coordinate it mirrors
_PLANES = {"yz": 0, "xz": 1, "xy": 2}


def _rank(boxes: Mapping[int, Box], part_ids: Iterable[int]) -> list[int]:
    return sorted(part_ids, key=lambda i: (-boxes[i].volume, i))


def star(boxes: Mapping[int, Box], part_ids: Iterable[int]) -> Structure:
    """Largest part as the root, all others rigid children of it."""
    order = _rank(boxes, part_ids)
    nodes = {i: Node(None if i == order[0] else order[0], 0) for i in sorted(order)}
    return Structure(dict(_MATERIALS), nodes, ())


def _bounds(b: Box) -> tuple[np.ndarray, np.ndarray]:
    c, e = np.asarray(b.centroid, float), np.asarray(b.extent, float)
    return c - e / 2, c + e / 2


def _contains(outer: Box, inner: Box) -> bool:
    lo_o, hi_o = _bounds(outer)
    lo_i, hi_i = _bounds(inner)
    return bool(np.all(lo_i >= lo_o - CONTAIN_TOL) and np.all(hi_i <= hi_o + CONTAIN_TOL))


def _gap_and_contact(a: Box, b: Box) -> tuple[float, float]:
    """Euclidean gap between two boxes (0 if they touch) and the area of their touching faces."""
    lo_a, hi_a = _bounds(a)
    lo_b, hi_b = _bounds(b)
    overlap = np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b)
    gap = float(np.linalg.norm(np.maximum(0.0, -overlap)))
    two_largest = np.sort(np.maximum(overlap, 0.0))[1:]
    return gap, float(two_largest[0] * two_largest[1])


def _parent(part: int, higher: list[int], boxes: Mapping[int, Box]) -> int | None:
    containers = [q for q in higher if _contains(boxes[q], boxes[part])]
    if containers:
        return min(containers, key=lambda q: (boxes[q].volume, q))
    touching = []
    for q in higher:
        gap, area = _gap_and_contact(boxes[part], boxes[q])
        if gap <= TOUCH_TOL:
            touching.append((round(gap, 3), -area, q))
    return min(touching)[2] if touching else None


def _reaches_front(part: Box, parent: Box) -> bool:
    lo, hi = _bounds(part)
    front = _bounds(parent)[0][1]
    return bool(lo[1] <= front + FRONT_TOL and hi[1] >= front - FRONT_TOL)


def _joint(part: Box, parent: Box) -> Joint | None:
    ex, ey, ez = part.extent
    if not _reaches_front(part, parent):
        return None
    cx, cy, cz = part.centroid
    if ey <= THIN_RATIO * min(ex, ez):
        lo, hi = _bounds(part)
        plo, phi = _bounds(parent)
        left = abs(lo[0] - plo[0]) <= abs(hi[0] - phi[0])
        # Left-edge hinge: the door extends along +X, so opening towards -Y is a negative angle.
        edge, rng = (lo[0], (-math.pi / 2, 0.0)) if left else (hi[0], (0.0, math.pi / 2))
        return Joint("hinge", (0.0, 0.0, 1.0), (float(edge), float(hi[1]), cz), rng)
    if min(part.extent) >= THIN_RATIO * max(part.extent) and _contains(parent, part):
        return Joint("slide", (0.0, -1.0, 0.0), (cx, cy, cz), (0.0, SLIDE_FRACTION * ey))
    return None


def _relations(nodes: Mapping[int, Node], boxes: Mapping[int, Box]) -> tuple[Relation, ...]:
    groups: dict[int | None, list[int]] = {}
    for i, n in nodes.items():
        groups.setdefault(n.parent, []).append(i)
    relations = []
    for parent, siblings in groups.items():
        if parent is None:
            continue
        centre = np.asarray(boxes[parent].centroid, float)
        for a, b in itertools.combinations(sorted(siblings), 2):
            if not np.allclose(sorted(boxes[a].extent), sorted(boxes[b].extent), atol=SIZE_TOL):
                continue
            ca, cb = np.asarray(boxes[a].centroid, float), np.asarray(boxes[b].centroid, float)
            plane = next(
                (
                    name for name, k in _PLANES.items()
                    if abs(ca[k] + cb[k] - 2 * centre[k]) <= MIRROR_TOL and abs(ca[k] - cb[k]) > MIRROR_TOL
                    and np.allclose(np.delete(ca, k), np.delete(cb, k), atol=MIRROR_TOL)
                ),
                None,
            )
            relations.append(Relation("symmetric", a, b, plane) if plane else Relation("instance", a, b))
    return tuple(relations)


def heuristic(boxes: Mapping[int, Box], part_ids: Iterable[int]) -> Structure:
    """Containment / adjacency tree with door and drawer joints and size-matched relations."""
    order = _rank(boxes, part_ids)
    nodes: dict[int, Node] = {}
    for rank, part in enumerate(order):
        parent = _parent(part, order[:rank], boxes)
        joint = None if parent is None else _joint(boxes[part], boxes[parent])
        nodes[part] = Node(parent, 0, joint)
    nodes = dict(sorted(nodes.items()))
    return Structure(dict(_MATERIALS), nodes, _relations(nodes, boxes))


BOX_BASELINES = {"star": star, "heuristic": heuristic}
