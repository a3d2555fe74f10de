"""Canonical form of a structure (SPEC §2), applied to every target and to predictions before metrics.

Two structures that describe the same articulated object in different but equivalent ways (another
root, an axis pointing the other way with a mirrored range, an instance group written as a chain)
become identical, so that the model is trained on one spelling and metrics compare like with like.

Every decision that depends on a number is taken on the value as ``to_json`` writes it (3
decimals; box extents at BOX_DECIMALS), so canonicalising a structure before or after a JSON round
trip gives the same bytes, and canonicalize is idempotent.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from jax3dc.errors import StructureError
from jax3dc.structure.boxes import BOX_DECIMALS
from jax3dc.structure.schema import Box, Joint, Node, Relation, Structure
from jax3dc.structure.serialize import round_number, rounded_axis
from jax3dc.structure.union_find import connected_sets


_UNIT_TOLERANCE = 1e-12


def is_degenerate(j: Joint) -> bool:
    """A joint that cannot move: zero or non-finite axis, or a range of zero length as written."""
    axis = [float(c) for c in j.axis]
    if len(axis) != 3 or not all(math.isfinite(c) for c in axis) or not any(axis):
        return True
    lo, hi = (float(v) for v in j.range)
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return True
    return round_number(lo) == round_number(hi)


def reversed_joint(j: Joint) -> Joint:
    """The same joint seen from the other body: pivot and axis kept, range [-hi, -lo]."""
    lo, hi = j.range
    return Joint(j.type, j.axis, j.pivot, (-float(hi), -float(lo)))


def oriented_joint(j: Joint) -> Joint:
    """Unit axis whose largest-magnitude component (as written, first on ties) is positive."""
    axis = tuple(float(c) for c in j.axis)
    norm = math.sqrt(sum(c * c for c in axis))
    if abs(norm - 1.0) > _UNIT_TOLERANCE:  # renormalising a unit vector again would drift by ulps
        axis = tuple(c / norm for c in axis)
    written = rounded_axis(axis)
    biggest = max(abs(c) for c in written)
    k = next(i for i, c in enumerate(written) if abs(c) == biggest)
    if written[k] < 0:
        lo, hi = j.range
        return Joint(j.type, tuple(-c for c in axis), j.pivot, (-float(hi), -float(lo)))
    return Joint(j.type, axis, j.pivot, j.range)


def volume_key(box: Box) -> int:
    """Box volume in units of (10^-BOX_DECIMALS nu)^3, exact and independent of the axis order, so
    that equal parts tie exactly and ties go to the smaller id."""
    scale = 10**BOX_DECIMALS
    out = 1
    for e in box.extent:
        out *= max(0, int(round(float(e) * scale)))
    return out


def _trees(nodes: Mapping[int, Node]) -> list[list[int]]:
    """Node ids of each tree (root first, breadth-first); refuses a parent map with a cycle."""
    children: dict[int, list[int]] = {i: [] for i in nodes}
    for i, n in nodes.items():
        if n.parent is not None:
            if n.parent not in nodes:
                raise StructureError("parent_exists", f"node {i} parent", f"parent {n.parent} is not a node")
            children[n.parent].append(i)
    trees = []
    for root in sorted(i for i, n in nodes.items() if n.parent is None):
        order = [root]
        for i in order:
            order.extend(sorted(children[i]))
        trees.append(order)
    reached = sum(len(t) for t in trees)
    if reached != len(nodes):
        raise StructureError("cycle", "nodes", f"{len(nodes) - reached} nodes are on or below a parent cycle")
    return trees


def reroot(nodes: dict[int, Node], new_root: int) -> None:
    """Make ``new_root`` the root of its tree in place, moving joints along the reversed path."""
    path = [new_root]
    while nodes[path[-1]].parent is not None:
        path.append(nodes[path[-1]].parent)
    old = {i: nodes[i] for i in path}
    nodes[new_root] = Node(None, old[new_root].material, None, old[new_root].name)
    for child, parent in zip(path, path[1:]):
        j = old[child].joint
        nodes[parent] = Node(child, old[parent].material, None if j is None else reversed_joint(j), old[parent].name)


def canonical_relations(relations: tuple[Relation, ...]) -> tuple[Relation, ...]:
    """Symmetric pairs with a < b, instance groups as stars at their smallest id, support kept;
    duplicates removed; sorted by (type, a, b)."""
    out: set[tuple[str, int, int, str]] = set()
    instances = [(r.a, r.b) for r in relations if r.type == "instance"]
    for r in relations:
        if r.type == "symmetric":
            out.add((r.type, min(r.a, r.b), max(r.a, r.b), r.plane or ""))
        elif r.type != "instance":
            out.add((r.type, r.a, r.b, r.plane or ""))
    for anchor, *others in connected_sets({i for pair in instances for i in pair}, instances):
        out.update(("instance", anchor, i, "") for i in others)
    return tuple(Relation(t, a, b, plane or None) for t, a, b, plane in sorted(out))


def canonicalize(s: Structure, boxes: Mapping[int, Box]) -> Structure:
    """The canonical form of ``s`` (SPEC §2 steps 1-5); ``boxes`` gives each part's volume."""
    missing = sorted(set(s.nodes) - set(boxes))
    if missing:
        raise StructureError("box_missing", f"node {missing[0]}",
                             f"no bounding box for parts {', '.join(map(str, missing[:10]))}")
    # 1-2: sorted ids; degenerate joints become rigid attachments; axes unit length.
    nodes: dict[int, Node] = {}
    for i, n in sorted(s.nodes.items()):
        joint = n.joint
        if joint is not None and is_degenerate(joint):
            joint = None
        nodes[i] = Node(n.parent, n.material, joint, n.name)
    # 3: each tree rooted at its part of largest box volume (ties: smallest id).
    for tree in _trees(nodes):
        best = min(tree, key=lambda i: (-volume_key(boxes[i]), i))
        if best != tree[0]:
            reroot(nodes, best)
    # 4: axis sign.
    for i, n in nodes.items():
        if n.joint is not None:
            nodes[i] = Node(n.parent, n.material, oriented_joint(n.joint), n.name)
    # 5 (and the relation part of 1).
    return Structure(
        materials=dict(sorted(s.materials.items())),
        nodes=dict(sorted(nodes.items())),
        relations=canonical_relations(s.relations),
    )
