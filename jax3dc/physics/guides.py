"""A slide child's guide: the part it runs in, which it may not leave in any pose.

A drawer runs in its carcass: across its slide axis the carcass's extent contains the drawer's,
and along the axis they overlap by most of the drawer's depth. When that part is the drawer's
parent, the sweep check (``verdict``: "slides out of its guide") keeps the drawer in it. When the
parent does not contain the drawer across the axis but another part does (a drawer hung on the
drawer beside it, still sitting in the carcass's slot), the carcass is still what it runs in, and
the joints between the two (its own and the neighbour's) add up: with both opened the drawer
is carried out of the slot it runs in, held by nothing that guides it. Pure numpy on the
rest-frame meshes, over every combination of the chain's range ends.
"""

from __future__ import annotations

import itertools

import numpy as np
import trimesh

from jax3dc.physics.kinematics import joint_motion
from jax3dc.physics.tolerances import GUIDE_ENCLOSE_TOL_NU, SLIDE_GUIDE_OVERLAP_NU
from jax3dc.structure.schema import Structure


def carried_out_of_guide(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int
                         ) -> tuple[int, dict[int, float]] | None:
    """(guide part, {jointed part: value}) of the first range-end combination of the joints
    between a slide child and its guide (when the guide is not its parent's rigid body) that
    moves the child clear of the guide along its axis; None when there is none."""
    node = structure.nodes[part]
    if node.joint is None or node.joint.type != "slide":
        return None
    basis = _basis(np.asarray(node.joint.axis, dtype=np.float64))
    body = _rigid(structure, part)
    child = np.concatenate([np.asarray(parts[p].vertices, dtype=np.float64) for p in body])
    if _encloses(np.concatenate([np.asarray(parts[p].vertices, dtype=np.float64)
                                 for p in welded(structure, node.parent)]), child, basis):
        return None  # its parent is its guide: the sweep check keeps it there
    chain = _chain(structure, part)  # jointed parts from the child up to its root
    for guide in sorted(structure.nodes):
        if guide in structure.subtree(part) or guide in welded(structure, node.parent):
            continue
        if not _encloses(np.asarray(parts[guide].vertices, dtype=np.float64), child, basis):
            continue
        # joints that move the child but not the guide: those below the guide's own ancestors
        guide_chain = set(_chain(structure, guide))
        between = [p for p in chain if p not in guide_chain]
        lo, hi = _along(np.asarray(parts[guide].vertices, dtype=np.float64), basis[0])
        for ends in itertools.product((0, 1), repeat=len(between)):
            values = {p: structure.nodes[p].joint.range[e] for p, e in zip(between, ends)}
            points = child
            for p in between:  # the child's own joint first, then each ancestor's
                points = joint_motion(structure.nodes[p].joint, values[p], points)
            clo, chi = _along(points, basis[0])
            if min(chi, hi) - max(clo, lo) <= 0.0:
                return guide, values
    return None


def _encloses(holder: np.ndarray, child: np.ndarray, basis: np.ndarray) -> bool:
    """The holder's extent contains the child's across the axis (within GUIDE_ENCLOSE_TOL_NU),
    and along it they overlap by at least SLIDE_GUIDE_OVERLAP_NU."""
    for k in (1, 2):
        hlo, hhi = _along(holder, basis[k])
        clo, chi = _along(child, basis[k])
        if clo < hlo - GUIDE_ENCLOSE_TOL_NU or chi > hhi + GUIDE_ENCLOSE_TOL_NU:
            return False
    hlo, hhi = _along(holder, basis[0])
    clo, chi = _along(child, basis[0])
    return min(chi, hhi) - max(clo, hlo) >= SLIDE_GUIDE_OVERLAP_NU


def _along(points: np.ndarray, direction: np.ndarray) -> tuple[float, float]:
    t = points @ direction
    return float(t.min()), float(t.max())


def _basis(axis: np.ndarray) -> np.ndarray:
    """Rows: the unit axis and two unit directions across it."""
    a = axis / np.linalg.norm(axis)
    u = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    return np.stack([a, u, np.cross(a, u)])


def _chain(structure: Structure, part: int) -> list[int]:
    out, p = [], part
    while p is not None:
        if structure.nodes[p].joint is not None:
            out.append(p)
        p = structure.nodes[p].parent
    return out


def _rigid(structure: Structure, part: int) -> list[int]:
    """The part and the descendants fixed to it (a drawer and its handle)."""
    out, stack = [part], [part]
    while stack:
        for c in structure.children(stack.pop()):
            if structure.nodes[c].joint is None:
                out.append(c)
                stack.append(c)
    return out


def welded(structure: Structure, part: int) -> set[int]:
    """The parts rigidly joined to ``part`` (itself, and through unjointed parent/child links)."""
    out, stack = {part}, [part]
    while stack:
        p = stack.pop()
        node = structure.nodes[p]
        linked = list(structure.children(p)) + ([node.parent] if node.parent is not None and node.joint is None else [])
        for q in linked:
            if q not in out and (q == node.parent or structure.nodes[q].joint is None):
                out.add(q)
                stack.append(q)
    return out
