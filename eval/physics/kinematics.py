"""Forward kinematics of a structure in numpy (rest-frame joints), for comparing two articulations.

A joint's pivot and axis are given in the rest pose's object frame, so a point of a part moves by
its own joint first, then by each ancestor's joint in turn.
"""

from __future__ import annotations

import numpy as np
import trimesh

from jax3dc.structure.schema import Joint, Structure

SAMPLE_STATES = 8  # random states (each joint at the same fraction of its own range in both structures)
SAMPLE_VERTICES = 256


def joint_motion(joint: Joint, value: float, points: np.ndarray) -> np.ndarray:
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis /= np.linalg.norm(axis)
    if joint.type == "slide":
        return points + value * axis
    pivot = np.asarray(joint.pivot, dtype=np.float64)
    c, s = np.cos(value), np.sin(value)
    r = points - pivot
    rotated = r * c + np.cross(axis, r) * s + np.outer(r @ axis, axis) * (1 - c)  # Rodrigues
    return rotated + pivot


def posed(structure: Structure, part: int, points: np.ndarray, fractions: dict[int, float]) -> np.ndarray:
    """``points`` of ``part`` (rest pose) moved by every joint from the part up to its root."""
    p = part
    while p is not None:
        node = structure.nodes[p]
        if node.joint is not None:
            lo, hi = node.joint.range
            points = joint_motion(node.joint, lo + fractions.get(p, 0.0) * (hi - lo), points)
        p = node.parent
    return points


def subtree_vertices_at(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int, seed: int = 0) -> np.ndarray:
    """[SAMPLE_STATES, n, 3] positions of the part's vertices over random states of all joints."""
    rng = np.random.default_rng(seed)
    vertices = np.asarray(parts[part].vertices, dtype=np.float64)
    vertices = vertices[np.linspace(0, len(vertices) - 1, min(SAMPLE_VERTICES, len(vertices))).astype(int)]
    ids = sorted(structure.nodes)
    out = []
    for _ in range(SAMPLE_STATES):
        fractions = dict(zip(ids, rng.uniform(0.0, 1.0, len(ids))))
        out.append(posed(structure, part, vertices, fractions))
    return np.stack(out)
