"""Mutations of a correct structure, each of which breaks its articulation in a known way.

Used to measure how often the checks catch a wrong prediction, and whether for the right reason.
Each mutation names the checks (``jax3dc.physics.findings.CHECKS``) a finding of which on the mutated
joint counts as a correct flag: the groups below, named by how their reasons start.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Iterable

import numpy as np
import trimesh

from jax3dc.physics.findings import Finding
from jax3dc.structure.schema import Joint, Structure

PIVOT_SHIFT_NU = 0.25  # how far "pivot moved" moves the pivot off the part boundary
PENETRATES = ("rest parent", "penetration", "crossing", "floor")  # "penetrates ..."
DETACHED = ("detached", "lifted off", "guide", "carried out of guide", "rest gap")  # "detached from ..."
PIVOT = ("pivot",)  # "pivot detached"
LIMIT = ("limit",)  # "limit unreachable" (a failure) or "limit past contact" (a warning)
# "disagrees with part": its mirror twin or duplicate articulates otherwise
RELATION = ("relation parents", "relation joint type", "relation motion")


@dataclass(frozen=True)
class Mutation:
    kind: str
    part: int  # the jointed part whose joint (or parent) was changed
    structure: Structure
    expected: tuple[str, ...]  # the checks whose findings count as the right flag

    def caught(self, findings: Iterable[Finding]) -> bool:
        """Whether one of ``findings`` (those on the mutated joint) is of an expected check."""
        return any(f.check in self.expected for f in findings)


def mutations_of(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> list[Mutation]:
    """Every applicable mutation of every joint (see the module docstring for the kinds)."""
    out: list[Mutation] = []
    centroids = {p: np.asarray(m.bounds, dtype=np.float64).mean(axis=0) for p, m in parts.items()}
    for part, node in structure.nodes.items():
        joint = node.joint
        if joint is None:
            continue
        axis = np.asarray(joint.axis, dtype=np.float64)
        motion = PENETRATES + DETACHED + LIMIT + RELATION
        out.append(Mutation("flipped axis", part, _with_joint(structure, part, dataclasses.replace(
            joint, axis=tuple(-axis))), motion))
        out.append(Mutation("range doubled", part, _with_joint(structure, part, dataclasses.replace(
            joint, range=_doubled(joint))), motion))
        swapped = "slide" if joint.type == "hinge" else "hinge"
        out.append(Mutation("hinge-slide swapped", part, _with_joint(structure, part, dataclasses.replace(
            joint, type=swapped)), motion + PIVOT))
        if joint.type == "hinge":  # a slide's pivot does not change its motion
            shift = _away_from(centroids[part], np.asarray(joint.pivot), axis)
            out.append(Mutation("pivot moved", part, _with_joint(structure, part, dataclasses.replace(
                joint, pivot=tuple(np.asarray(joint.pivot) + PIVOT_SHIFT_NU * shift))), PIVOT + motion))
        far = _farthest_other_part(structure, part, centroids)
        if far is not None:
            out.append(Mutation("attached to a far part", part, _with_parent(structure, part, far),
                                PIVOT + DETACHED + PENETRATES + RELATION))
        wrong = _other_non_descendant(structure, part, node.parent, centroids)
        if wrong is not None and wrong != far:
            out.append(Mutation("wrong parent", part, _with_parent(structure, part, wrong),
                                PIVOT + DETACHED + PENETRATES + RELATION))
    return out


def _doubled(joint: Joint) -> tuple[float, float]:
    """The span doubled at the end away from rest (hinges kept within the schema's ±2π)."""
    lo, hi = joint.range
    span = hi - lo
    limit = 2 * np.pi if joint.type == "hinge" else np.inf
    if abs(hi) >= abs(lo):
        return (lo, float(min(hi + span, limit)))
    return (float(max(lo - span, -limit)), hi)


def _away_from(centroid: np.ndarray, pivot: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Unit direction perpendicular to the axis pointing from the part's centroid to the pivot."""
    axis = axis / np.linalg.norm(axis)
    d = pivot - centroid
    d = d - (d @ axis) * axis
    if np.linalg.norm(d) < 1e-6:
        d = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    return d / np.linalg.norm(d)


def _farthest_other_part(structure: Structure, part: int, centroids) -> int | None:
    candidates = [p for p in structure.nodes if p not in structure.subtree(part) and p != structure.nodes[part].parent]
    if not candidates:
        return None
    return max(candidates, key=lambda p: float(np.linalg.norm(centroids[p] - centroids[part])))


def _other_non_descendant(structure: Structure, part: int, parent: int | None, centroids) -> int | None:
    """The nearest part (by centroid) that is neither the parent nor in the part's own subtree."""
    candidates = [p for p in structure.nodes if p not in structure.subtree(part) and p != parent]
    if not candidates:
        return None
    return min(candidates, key=lambda p: float(np.linalg.norm(centroids[p] - centroids[part])))


def _with_joint(structure: Structure, part: int, joint: Joint) -> Structure:
    nodes = dict(structure.nodes)
    nodes[part] = dataclasses.replace(nodes[part], joint=joint)
    return dataclasses.replace(structure, nodes=nodes)


def _with_parent(structure: Structure, part: int, parent: int) -> Structure:
    nodes = dict(structure.nodes)
    nodes[part] = dataclasses.replace(nodes[part], parent=parent)
    return dataclasses.replace(structure, nodes=nodes)
