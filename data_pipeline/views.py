"""Posed views of an articulated object (SPEC §4): one joint moved from rest by θ.

The moved subtree's meshes, pivots and axes are transformed rigidly, and the moved joint's range
becomes [lo − θ, hi − θ], so the structure describes the pose shown in the image.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import trimesh

from jax3dc.structure import Joint, Structure


@dataclass(frozen=True)
class PosedObject:
    """Parts and structure in one pose; ``poses`` maps each moved part to its 4x4 rigid transform."""

    structure: Structure
    parts: dict[int, trimesh.Trimesh]
    poses: dict[int, np.ndarray]
    moved_joint: int | None = None
    theta: float = 0.0


def subtree(structure: Structure, root: int) -> list[int]:
    return sorted(structure.subtree(root))


def joint_transform(joint: Joint, theta: float) -> np.ndarray:
    """4x4 motion of a joint moved by θ (radians about the axis through the pivot, or nu along it)."""
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    if joint.type == "slide":
        m = np.eye(4)
        m[:3, 3] = axis * theta
        return m
    return trimesh.transformations.rotation_matrix(theta, axis, np.asarray(joint.pivot, dtype=np.float64))


def _moved_joint(j: Joint, m: np.ndarray) -> Joint:
    pivot = m[:3, :3] @ np.asarray(j.pivot) + m[:3, 3]
    axis = m[:3, :3] @ np.asarray(j.axis)
    return replace(j, pivot=tuple(float(v) for v in pivot), axis=tuple(float(v) for v in axis))


def move_joint(structure: Structure, parts: dict[int, trimesh.Trimesh], part_id: int, theta: float) -> PosedObject:
    """The object with the joint of ``part_id`` moved from rest by ``theta``."""
    joint = structure.nodes[part_id].joint
    if joint is None:
        raise ValueError(f"part {part_id} has no joint")
    m = joint_transform(joint, theta)
    moved = subtree(structure, part_id)
    nodes = dict(structure.nodes)
    new_parts = dict(parts)
    for pid in moved:
        node = nodes[pid]
        j = node.joint
        if pid == part_id:
            j = replace(joint, range=(joint.range[0] - theta, joint.range[1] - theta))
        elif j is not None:
            j = _moved_joint(j, m)
        nodes[pid] = replace(node, joint=j)
        new_parts[pid] = parts[pid].copy()
        new_parts[pid].apply_transform(m)
    return PosedObject(replace(structure, nodes=nodes), new_parts, {pid: m for pid in moved}, part_id, theta)


def at_rest(structure: Structure, parts: dict[int, trimesh.Trimesh]) -> PosedObject:
    return PosedObject(structure, parts, {})


def sample_view_pose(structure: Structure, parts: dict[int, trimesh.Trimesh], view: int,
                     rng: np.random.Generator) -> PosedObject:
    """View 0 is the rest pose; view v ≥ 1 moves joint number (v−1) mod J to a value drawn from
    the inner part of its range (away from the rest value, so the pose visibly differs)."""
    joints = structure.joints()
    if view == 0 or not joints:
        return at_rest(structure, parts)
    pid = sorted(joints)[(view - 1) % len(joints)]
    lo, hi = joints[pid].range
    theta = float(rng.uniform(lo + 0.2 * (hi - lo), lo + 0.9 * (hi - lo)))
    return move_joint(structure, parts, pid, theta)
