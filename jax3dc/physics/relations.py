"""Related parts must articulate alike: the structure's own relations as a check of its joints.

A ``symmetric`` pair (mirror images) or an ``instance`` pair (linked duplicates) moves alike under
a map that carries one part onto the other, on the same or related parents: a wardrobe's left
door opening outwards and its twin inwards, or twice as far, cannot both be right. Physics alone
sees no fault when the odd door swings through empty space; the declared relation does. The
candidate maps are the translation between the two parts and the mirrors across the axis planes
half-way between them, each kept only where it carries one part's box onto the other's: a door
board duplicated as an instance may hang on either edge, so a duplicate may move as a mirror
image too. A pair that no candidate fits (a rotated duplicate, a loose relation) is left alone,
and so is a pair of which only one part has a joint (a sliding window's fixed pane and its sash).
For a pair, which of the two is wrong cannot be told: both joints get the reason. Pure numpy on
the rest-frame meshes.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import trimesh

from jax3dc.physics.findings import Finding
from jax3dc.physics.kinematics import same_line, subtree_points, sweep_distance, symmetric_about
from jax3dc.physics.tolerances import RELATION_FIT_NU, RELATION_MOTION_TOL_NU
from jax3dc.structure.schema import Joint, Relation, Structure

def relation_disagreements(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> list[Finding]:
    """A finding ("relation parents|joint type|motion", shown as "disagrees with part B
    (symmetric|instance): ...") per jointed part of each related pair whose articulations are not
    each other's image under the relation's map."""
    out: list[Finding] = []
    for relation in structure.relations:
        if relation.type not in ("symmetric", "instance"):
            continue
        a, b = relation.a, relation.b
        if a not in parts or b not in parts:
            continue
        maps = _maps(parts[a], parts[b])
        if not maps:
            continue
        problem = _disagreement(structure, parts, relation, maps)
        if problem is None:
            continue
        for this, other in ((a, b), (b, a)):
            if structure.nodes[this].joint is not None:
                out.append(dataclasses.replace(problem, joints=(this,), parts=(other,) + problem.parts,
                                               relation=relation.type))
    return out


class _Map:
    """The relation's rigid map of the object frame: x -> linear @ x + shift, and whether it mirrors."""

    def __init__(self, linear: np.ndarray, shift: np.ndarray):
        self.linear, self.shift = linear, shift
        self.mirrors = bool(np.linalg.det(linear) < 0)

    def points(self, x: np.ndarray) -> np.ndarray:
        return x @ self.linear.T + self.shift

    def joint(self, joint: Joint) -> Joint:
        """The image of a joint: a hinge's axis is a pseudo-vector (a mirror reverses the turn)."""
        axis = self.linear @ np.asarray(joint.axis, dtype=np.float64)
        if joint.type == "hinge" and self.mirrors:
            axis = -axis
        pivot = self.points(np.asarray(joint.pivot, dtype=np.float64)[None])[0]
        return dataclasses.replace(joint, axis=tuple(axis), pivot=tuple(pivot))


def _maps(a: trimesh.Trimesh, b: trimesh.Trimesh) -> list[_Map]:
    """The translation from part a to part b and the mirrors half-way between them that carry a's
    box onto b's (within RELATION_FIT_NU)."""
    box_a, box_b = np.asarray(a.bounds, dtype=np.float64), np.asarray(b.bounds, dtype=np.float64)
    ca, cb = box_a.mean(axis=0), box_b.mean(axis=0)
    candidates = [_Map(np.eye(3), cb - ca)]
    middle = (ca + cb) / 2
    for axis in range(3):
        linear = np.eye(3)
        linear[axis, axis] = -1.0
        candidates.append(_Map(linear, middle - linear @ middle))
    out = []
    for mapping in candidates:
        image = mapping.points(box_a)
        image = np.stack([image.min(axis=0), image.max(axis=0)])
        if np.max(np.abs(image - box_b)) <= RELATION_FIT_NU:
            out.append(mapping)
    return out


def _disagreement(structure: Structure, parts: dict[int, trimesh.Trimesh], relation: Relation,
                  maps: list[_Map]) -> Finding | None:
    """What differs, as a finding without its joint and related part (the caller adds them)."""
    a, b = structure.nodes[relation.a], structure.nodes[relation.b]
    if a.joint is None or b.joint is None:
        return None
    if a.parent != b.parent and not _related(structure, a.parent, b.parent):
        return Finding("relation parents", parts=(a.parent, b.parent))
    if a.joint.type != b.joint.type:
        return Finding("relation joint type", joint_types=(a.joint.type, b.joint.type))
    points = subtree_points(structure, parts, relation.b)
    if b.joint.type == "hinge" and symmetric_about(points, b.joint) and any(
            same_line(m.joint(a.joint), b.joint, RELATION_MOTION_TOL_NU) for m in maps):
        return None  # a round part turned about its own axis: any range occupies the same space
    gap = min(sweep_distance(m.joint(a.joint), b.joint, points) for m in maps)
    if gap > RELATION_MOTION_TOL_NU:
        return Finding("relation motion", depth=float(gap))
    return None


def _related(structure: Structure, p: int | None, q: int | None) -> bool:
    if p is None or q is None:
        return False
    return any({r.a, r.b} == {p, q} for r in structure.relations)

