"""Split and merge augmentations (SPEC §4); S is re-rendered from the changed parts.

* split: an articulated leaf is cut by a plane through its centroid (normal along its longest
  box side); the second piece becomes a new sibling with the same parent, material and joint.
  The cut faces are left open (capping needs shapely, not a dependency); the two pieces stay in
  contact, so no render shows inside them.
* merge: two sibling leaves that are both rigid, or whose joints match within tolerance (same
  type, parallel axes, pivots on the same axis line, same range), become one part; ids above
  the removed one shift down so ids stay 1..N.
* fuse: every rigid leaf that sits on a moving part (a door's handle, a lid's latch, a laptop
  lid's display) or is a handle or knob becomes part of the mesh it sits on. The factories model
  such pieces as parts of their own, while a real object's link carries its handle in the same
  mesh: S then shows a door with no handle, and the model must find the handle in I to put the
  hinge on the other edge. Training on both conventions keeps that from marking the domain.
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
FUSED_NAMES = ("handle", "knob", "latch")  # rigid leaves fused wherever they sit (names contain one)


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
    return replace(_remove_part(obj, gone, keep), program=None, parameters=None, augmentation=f"merge-{keep}-{gone}")


def _remove_part(obj: SourceObject, gone: int, into: int) -> SourceObject:
    """``obj`` with part ``gone``'s mesh added to part ``into``'s and ``gone`` removed; ids above it
    shift down so ids stay 1..N. Only support relations are kept (those not naming ``gone``): the
    symmetric and instance ones no longer hold for a changed mesh, and records find them again
    from the meshes (``object_records``)."""
    s = obj.structure
    renumber = {p: p - (p > gone) for p in s.nodes if p != gone}
    nodes = {renumber[p]: replace(n, parent=None if n.parent is None else renumber[n.parent])
             for p, n in s.nodes.items() if p != gone}
    relations = tuple(replace(r, a=renumber[r.a], b=renumber[r.b]) for r in s.relations
                      if gone not in (r.a, r.b) and r.type == "support")
    parts = {renumber[p]: m for p, m in obj.parts.items() if p != gone}
    parts[renumber[into]] = trimesh.util.concatenate([obj.parts[into], obj.parts[gone]])
    return replace(obj, structure=replace(s, nodes=nodes, relations=relations), parts=parts)


def _fusable(s: Structure, pid: int) -> bool:
    node = s.nodes[pid]
    if node.joint is not None or node.parent is None:
        return False
    named = any(word in (node.name or "") for word in FUSED_NAMES)
    return named or s.nodes[node.parent].joint is not None


def fuse_handles(obj: SourceObject) -> SourceObject | None:
    """``obj`` with its handles, knobs and the other rigid leaves of moving parts fused into the
    parts they sit on (repeatedly, so a leaf's leaf goes too), or None when nothing fuses."""
    fused = obj
    while True:
        s = fused.structure
        found = [p for p in leaves(s) if _fusable(s, p)]
        if not found:
            break
        fused = _remove_part(fused, found[-1], s.nodes[found[-1]].parent)  # the highest id: lower ids keep
    if fused is obj:
        return None
    return replace(fused, program=None, parameters=None, augmentation="fuse")
