"""Split and merge augmentations (SPEC §4); S is re-rendered from the changed parts.

* split: an articulated leaf is cut by a plane through its centroid (normal along its longest
  box side); the second piece becomes a new sibling with the same parent, material and joint.
  The cut faces are left open (capping needs shapely, not a dependency); the two pieces stay in
  contact, so no render shows inside them.
* merge: two sibling leaves that are both rigid, or whose joints match within tolerance (same
  type, parallel axes, pivots on the same axis line, same range), become one part; ids above
  the removed one shift down so ids stay 1..N.
"""

from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import numpy as np
import trimesh

from data_pipeline.samples import SourceObject
from jax3dc.structure import Joint, Structure

AXIS_TOL = 1e-3
PIVOT_TOL = 1e-3
RANGE_TOL = 1e-3


def leaves(structure: Structure) -> list[int]:
    parents = {n.parent for n in structure.nodes.values()}
    return [pid for pid in sorted(structure.nodes) if pid not in parents]


def joints_match(a: Joint | None, b: Joint | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    if a.type != b.type or not np.allclose(a.range, b.range, atol=RANGE_TOL):
        return False
    ua, ub = (np.asarray(j.axis, float) / np.linalg.norm(j.axis) for j in (a, b))
    if np.linalg.norm(np.cross(ua, ub)) > AXIS_TOL or ua @ ub < 0:
        return False
    if a.type == "slide":
        return True
    d = np.asarray(b.pivot, float) - np.asarray(a.pivot, float)
    return bool(np.linalg.norm(d - (d @ ua) * ua) < PIVOT_TOL)


def split_part(obj: SourceObject, rng: np.random.Generator) -> SourceObject | None:
    """``obj`` with one articulated leaf cut in two, or None when it has no articulated leaf."""
    s = obj.structure
    candidates = [p for p in leaves(s) if s.nodes[p].joint is not None]
    if not candidates:
        return None
    pid = candidates[int(rng.integers(len(candidates)))]
    mesh = obj.parts[pid]
    lo, hi = mesh.bounds
    normal = np.eye(3)[int(np.argmax(hi - lo))]
    origin = (lo + hi) / 2.0
    halves = [trimesh.Trimesh(*trimesh.intersections.slice_faces_plane(
        np.asarray(mesh.vertices), np.asarray(mesh.faces), sign * normal, origin)[:2], process=False)
        for sign in (1.0, -1.0)]
    if any(len(h.faces) == 0 for h in halves):
        return None
    new_id = max(s.nodes) + 1
    nodes = dict(s.nodes)
    nodes[new_id] = replace(s.nodes[pid], name=None)
    parts = dict(obj.parts)
    parts[pid], parts[new_id] = halves
    return replace(obj, structure=replace(s, nodes=nodes), parts=parts, program=None,
                   parameters=None, augmentation=f"split-{pid}")


def merge_parts(obj: SourceObject, rng: np.random.Generator) -> SourceObject | None:
    """``obj`` with two compatible sibling leaves made one part, or None when no pair qualifies."""
    s = obj.structure
    pairs = [(a, b) for a, b in combinations(leaves(s), 2)
             if s.nodes[a].parent is not None and s.nodes[a].parent == s.nodes[b].parent
             and joints_match(s.nodes[a].joint, s.nodes[b].joint)]
    if not pairs:
        return None
    keep, gone = pairs[int(rng.integers(len(pairs)))]
    renumber = {p: p - (p > gone) for p in s.nodes if p != gone}
    nodes = {renumber[p]: replace(n, parent=None if n.parent is None else renumber[n.parent])
             for p, n in s.nodes.items() if p != gone}
    relations = tuple(replace(r, a=renumber[r.a], b=renumber[r.b]) for r in s.relations
                      if gone not in (r.a, r.b) and r.type == "support")
    parts = {renumber[p]: m for p, m in obj.parts.items() if p != gone}
    parts[renumber[keep]] = trimesh.util.concatenate([obj.parts[keep], obj.parts[gone]])
    return replace(obj, structure=replace(s, nodes=nodes, relations=relations), parts=parts, program=None,
                   parameters=None, augmentation=f"merge-{keep}-{gone}")
