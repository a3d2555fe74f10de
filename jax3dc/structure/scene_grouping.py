"""Objects of a scene kept apart at decode time, from the parts' own boxes (issue 47).

In a scene (SPEC §4) different objects are separate bodies: pieces of furniture stand apart on
the floor, and an item on a piece of furniture touches it only where its base rests on the top
face. A model that reads the legend may still wire two objects into one tree (parent edges across
objects). This step reads the object partition from the legend boxes and fixes the model's tree:

1. **Bodies**: parts whose boxes touch (gap at most ``tol`` on every axis) are joined; each
   connected set is one body.
2. **Supports**: inside a body, the lowest horizontal plane with every part wholly above or wholly
   below it (a part within ``tol`` of both sides is above when its centre is: an item's base can be
   thinner than the legend's rounding), where each upper piece stands inside the top face of one
   lower part (footprint centre inside, footprint at most ``FOOTPRINT_SHARE`` of the face, height at
   least ``HEIGHT_SHARE`` of the lower side's, and the lower side at least ``HOST_SHARE`` of the
   scene's height), separates items from the furniture they stand on. An item is not cut again
   (its lid rests on its body); what is below may be.
3. **The model's joints**: a joint the model wrote between parts of two bodies keeps them in one
   object where the two are stacked (footprints overlapping, at most ``JOINT_REACH`` apart
   vertically: a keyboard tray under a desk top, a lid lifted off its box) or side by side at most
   ``SIDE_REACH`` apart (a door on its carcass). Farther side by side it does not: a cabinet standing
   3 cm beside a desk is another object however the model wired it.
4. **Regrouping**: a parent edge between parts of different objects is cut; within one object the
   model's edges are kept, and a piece left without its parent hangs, with the joint it had, from
   the nearest part of its object outside its own subtree.

The step runs only on a scene: where the model wrote several trees; where the legend shows two
bodies standing apart on the floor (pieces of furniture side by side; no single object of the
procedural build or the real sets has two); or where the model wrote a ``support`` relation (SPEC
§2: an object resting on another, written in scenes only) between parts the boxes place in two
objects. A single object's parts need not touch (a lifted lid, a desk's keyboard tray, knobs on a
stove top), and an item on a table has the boxes of a kettle's lid on its body or a tap on a
kitchen counter, so one tree without any of these cues is left exactly as written. Parts the
legend gives no box follow their parent. A valid structure stays valid: ids, materials and
relations are kept, and every cut leaves a forest.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import replace

import numpy as np

from jax3dc.structure.canonical import reroot
from jax3dc.structure.rewrite import rewrite_structure
from jax3dc.structure.schema import Box, Structure
from jax3dc.structure.serialize import to_dict
from jax3dc.structure.union_find import connected_sets

CONTACT_TOLERANCE = 0.004
"""nu: the largest gap between two boxes that still counts as contact. Legend numbers carry 3
decimals (up to 0.001 off per centroid and per half extent); the gaps the scene builder leaves
between objects (5 cm, 2.5 cm between items on one top) are 0.006 nu or more in a 4 m scene."""

FOOTPRINT_SHARE = 0.9
"""An item's footprint covers at most this share of the top it stands on; a lid or a table top
covers all of what holds it (and is part of that object)."""

HEIGHT_SHARE = 0.02
"""An item is at least this share of the height of what it stands on (a knob on a stove is not)."""

HOST_SHARE = 0.3
"""What items stand on is furniture, at least this share of the scene's height; a fan's head on its
stand, or a lid on a kettle, both on the floor beside a table, are parts of one item."""

JOINT_REACH = 0.06
"""nu: a joint the model writes between two stacked parts at most this far apart keeps them in one
object (a tray hangs under a desk top, a lid lifts off its box); farther, it is an error."""

SIDE_REACH = 0.01
"""nu: the same for two parts side by side. Real objects' doors and lids beside their bodies are at
most 0.01 apart; different objects side by side in the scene builds are 0.0135 or more apart, and
the joints the release model wrote between furniture side by side spanned 0.025 to 0.044."""


def _corners(boxes: Mapping[int, Box], ids: Iterable[int]) -> tuple[list[int], np.ndarray, np.ndarray]:
    ids = sorted(ids)
    c = np.asarray([boxes[i].centroid for i in ids], dtype=np.float64).reshape(-1, 3)
    e = np.abs(np.asarray([boxes[i].extent for i in ids], dtype=np.float64).reshape(-1, 3))
    return ids, c - e / 2, c + e / 2


def _components(ids: list[int], linked: np.ndarray) -> list[list[int]]:
    """Connected sets of ``ids`` under the symmetric boolean matrix ``linked`` (sorted lists,
    ordered by smallest id)."""
    return connected_sets(ids, ((ids[a], ids[b]) for a, b in zip(*np.nonzero(np.triu(linked, 1)))))


def _touching(lo: np.ndarray, hi: np.ndarray, tol: float) -> np.ndarray:
    gap = np.maximum(lo[:, None, :] - hi[None, :, :], lo[None, :, :] - hi[:, None, :])
    return (gap <= tol).all(axis=-1)


def _support_split(ids: list[int], lo: np.ndarray, hi: np.ndarray, tol: float,
                   scene_height: float) -> list[list[int]] | None:
    """The body ``ids`` cut at the lowest plane where items stand on a top face (step 2): the items
    (connected upper pieces) then the rest, or None."""
    row = {pid: k for k, pid in enumerate(ids)}
    for z in sorted(set(np.round(hi[:, 2], 6))):
        above, below = lo[:, 2] >= z - tol, hi[:, 2] <= z + tol
        upper = above & ((lo[:, 2] + hi[:, 2]) / 2 > z)  # a base thinner than tol is still above
        lower = ~upper
        if not (above | below).all() or not upper.any() or not lower.any():
            continue
        lower_height = hi[lower, 2].max() - lo[lower, 2].min()
        if lower_height < HOST_SHARE * scene_height:
            continue
        pieces = _components([i for i, u in zip(ids, upper) if u], _touching(lo[upper], hi[upper], tol))
        if all(_stands_on(lo[[row[p] for p in piece]].min(axis=0), hi[[row[p] for p in piece]].max(axis=0),
                          lo[lower], hi[lower], z, lower_height, tol) for piece in pieces):
            return pieces + [[i for i, low in zip(ids, lower) if low]]
    return None


def _stands_on(plo: np.ndarray, phi: np.ndarray, lo: np.ndarray, hi: np.ndarray, z: float, lower_height: float,
               tol: float) -> bool:
    """Whether the piece of box (plo, phi) stands at height ``z`` on the top face of one of the
    boxes (lo, hi) as an item does (module docstring, step 2)."""
    if plo[2] > z + tol:  # it reaches the lower parts only through other upper parts
        return False
    if phi[2] - plo[2] < HEIGHT_SHARE * lower_height:  # a knob on its own object's top
        return False
    centre = (plo[:2] + phi[:2]) / 2
    area = float(np.prod(phi[:2] - plo[:2]))
    tops = (np.abs(hi[:, 2] - z) <= tol) & (lo[:, :2] <= centre).all(axis=1) & (centre <= hi[:, :2]).all(axis=1)
    return bool((tops & (area <= FOOTPRINT_SHARE * np.prod(hi[:, :2] - lo[:, :2], axis=1))).any())


def bodies(boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE) -> list[list[int]]:
    """Parts joined by touching boxes (step 1), sorted lists ordered by smallest id."""
    ids, lo, hi = _corners(boxes, boxes)
    return _components(ids, _touching(lo, hi, tol))


def stands_apart(boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE) -> bool:
    """Whether at least two bodies stand on the floor (their lowest points within ``tol`` of the
    lowest of all boxes): the legend of a scene, read before the model's trees (module docstring)."""
    if not boxes:
        return False
    ids, lo, _ = _corners(boxes, boxes)
    row = {pid: k for k, pid in enumerate(ids)}
    floor = lo[:, 2].min()
    return sum(min(lo[row[p], 2] for p in body) <= floor + tol for body in bodies(boxes, tol)) >= 2


def object_groups(boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE,
                  scene_height: float | None = None) -> list[list[int]]:
    """The parts of each physical object (sorted lists, ordered by smallest id) from their boxes."""
    if not boxes:
        return []
    if scene_height is None:
        _, lo, hi = _corners(boxes, boxes)
        scene_height = float(hi[:, 2].max() - lo[:, 2].min())
    done: list[list[int]] = []
    for body in bodies(boxes, tol):
        b_ids, b_lo, b_hi = _corners(boxes, body)
        pieces = _support_split(b_ids, b_lo, b_hi, tol, scene_height) if len(body) > 1 else None
        if pieces is None:
            done.append(b_ids)
            continue
        *items, rest = pieces  # an item is not cut again: its lid rests on its body
        done.extend(items)
        done.extend(object_groups({p: boxes[p] for p in rest}, tol, scene_height))
    return sorted(done, key=lambda g: g[0])


def _axis_gaps(a: Box, b: Box) -> np.ndarray:
    """Gap between two boxes along each axis (negative: their spans overlap on that axis)."""
    ca, cb = np.asarray(a.centroid), np.asarray(b.centroid)
    half = (np.abs(np.asarray(a.extent)) + np.abs(np.asarray(b.extent))) / 2
    return np.abs(ca - cb) - half


def _gap(a: Box, b: Box) -> float:
    """Largest per-axis gap between two boxes (negative: they overlap on every axis)."""
    return float(_axis_gaps(a, b).max())


def _held_by_joint(child: Box, parent: Box, tol: float) -> bool:
    """Whether a joint between the two boxes keeps their bodies in one object (step 3): stacked
    within ``JOINT_REACH`` (every such joint of the scene builds: keyboard trays) or side by side
    within ``SIDE_REACH``."""
    gaps = _axis_gaps(child, parent)
    return bool(((gaps[:2] <= tol).all() and gaps[2] <= JOINT_REACH) or gaps.max() <= SIDE_REACH)


def object_of_parts(structure: Structure, boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE) -> dict[int, int]:
    """Part id -> object label: geometric objects (``object_groups``) joined where the model put a
    joint between two bodies that it holds together (step 3). A part without a box takes
    its parent's label (a root without a box is its own object)."""
    boxed = {p: boxes[p] for p in structure.nodes if p in boxes}
    label = {p: k for k, group in enumerate(object_groups(boxed, tol)) for p in group}
    body = {p: k for k, group in enumerate(bodies(boxed, tol)) for p in group}
    for child, node in structure.nodes.items():
        p = node.parent
        if (node.joint is not None and child in boxed and p in boxed and body[child] != body[p]
                and _held_by_joint(boxed[child], boxed[p], tol)):
            old, new = label[child], label[p]
            if old != new:
                label = {q: new if k == old else k for q, k in label.items()}

    def of(pid: int, seen: frozenset = frozenset()) -> int:
        if pid in label:
            return label[pid]
        parent = structure.nodes[pid].parent
        label[pid] = -pid if parent is None or parent in seen else of(parent, seen | {pid})
        return label[pid]

    return {pid: of(pid) for pid in sorted(structure.nodes)}


def _reads_as_scene(structure: Structure, boxes: Mapping[int, Box], tol: float) -> bool:
    """Whether ``structure`` over ``boxes`` is a scene (the module docstring's three cues)."""
    if len(structure.roots()) >= 2:
        return True
    boxed = {p: boxes[p] for p in structure.nodes if p in boxes}
    if stands_apart(boxed, tol):
        return True
    supports = [(r.a, r.b) for r in structure.relations if r.type == "support" and r.a in boxed and r.b in boxed]
    if not supports:
        return False
    label = {p: k for k, group in enumerate(object_groups(boxed, tol)) for p in group}
    return any(label[a] != label[b] for a, b in supports)


def regroup(structure: Structure, boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE) -> Structure:
    """``structure`` with one tree per object of ``object_of_parts`` (see the module docstring).

    A part cut from a parent in another object keeps the joint the model wrote on it where it can:
    hung from another piece of its own object, or, heading its object's only piece, with its
    object re-rooted at its largest other part (the joint is the part's motion against the rest of
    its object: a globe's stand wired with its hinge to the table turns against its globe), unless
    that re-rooting would take the joint the model wrote on the part below it (a wardrobe wired with
    a slide to a desk would take its drawer's slide): then the cut joint is dropped."""
    if not _reads_as_scene(structure, boxes, tol):
        return structure
    label = object_of_parts(structure, boxes, tol)
    nodes = dict(structure.nodes)
    loose: dict[int, bool] = {}  # local root -> whether it was cut from a parent
    for pid, node in nodes.items():
        if node.parent is None:
            loose[pid] = False
        elif label[pid] != label[node.parent]:
            loose[pid] = True
            nodes[pid] = replace(node, parent=None, joint=None)
    if not any(loose.values()) and len({label[r] for r in loose}) == len(loose):
        return structure

    def root_of(pid: int) -> int:
        while nodes[pid].parent is not None:
            pid = nodes[pid].parent
        return pid

    def volume(pid: int) -> float:
        return boxes[pid].volume if pid in boxes else -1.0

    tree = {pid: root_of(pid) for pid in nodes}  # part -> its local root
    for obj in sorted(set(label.values())):
        roots = sorted(r for r in loose if label[r] == obj)
        members = {r: sorted(p for p in nodes if tree[p] == r) for r in roots}
        size = {r: max(volume(p) for p in members[r]) for r in roots}
        main = max(roots, key=lambda r: (size[r], -r))
        placed = set(members[main])
        for r in sorted((r for r in roots if r != main), key=lambda r: (-size[r], r)):
            host = min(placed, key=lambda p: (_gap(boxes[p], boxes[r]) if p in boxes and r in boxes else np.inf, p))
            nodes[r] = replace(nodes[r], parent=host, joint=structure.nodes[r].joint if loose[r] else None)
            placed.update(members[r])
        joint = structure.nodes[main].joint if loose[main] else None
        others = sorted(p for p in placed - {main} if p in boxes)  # a part without a box is never a root
        if joint is not None and others:
            target = max(others, key=volume)
            below = target  # the part under ``main`` on the way to ``target``: its joint would go
            while nodes[below].parent != main:
                below = nodes[below].parent
            if nodes[below].joint is None:
                reroot(nodes, target)
                nodes[main] = replace(nodes[main], joint=joint)
    return replace(structure, nodes=nodes)


def regroup_text(text: str, boxes: Mapping[int, Box], tol: float = CONTACT_TOLERANCE) -> str:
    """A generated document regrouped (``regroup``); only parents and joints of the nodes that
    change are rewritten. A text that does not validate against the legend's ids is returned as
    it is (validation reports it downstream, as it should)."""

    def regrouped(structure: Structure, written: str) -> dict | None:
        grouped = regroup(structure, boxes, tol)
        changed = [p for p in grouped.nodes if grouped.nodes[p] != structure.nodes[p]]
        if not changed:
            return None
        doc = json.loads(written)
        nodes = to_dict(grouped)["nodes"]
        for pid in changed:
            node = doc["nodes"][str(pid)]
            node["parent"] = grouped.nodes[pid].parent
            node.pop("joint", None)
            if "joint" in nodes[str(pid)]:
                node["joint"] = nodes[str(pid)]["joint"]
        return doc

    return rewrite_structure(text, boxes, regrouped)
