"""Forward kinematics of a structure in numpy (rest-frame joints), for comparing two articulations.

A joint's pivot and axis are given in the rest pose's object frame, so a point of a part moves by
its own joint first, then by each ancestor's joint in turn.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from jax3dc.structure.schema import Joint, Structure

SAMPLE_STATES = 8  # random states (each joint at the same fraction of its own range in both structures)
SAMPLE_VERTICES = 256


def joint_motion(joint: Joint, value: float, points: np.ndarray) -> np.ndarray:
    axis = np.asarray(joint.axis, dtype=np.float64)
    axis /= np.linalg.norm(axis)
    if joint.type == "slide":
        return points + value * axis
    pivot = np.asarray(joint.pivot, dtype=np.float64)
    return Rotation.from_rotvec(axis * value).apply(points - pivot) + pivot


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


SAME_MOTION_TOL_NU = 0.01  # two motions whose reachable shapes all lie this close are the same (< PENETRATION_TOL_NU: no check can tell them apart)
SWEEP_SAMPLES = 33  # poses of one motion matched against the dense poses of the other


def subtree_points(structure: Structure, parts: dict[int, trimesh.Trimesh], part: int) -> np.ndarray:
    """[n, 3] rest-pose vertices (at most SAMPLE_VERTICES per part) of ``part`` and its descendants."""
    ids, stack = [], [part]
    while stack:
        p = stack.pop()
        ids.append(p)
        stack.extend(structure.children(p))
    out = []
    for p in ids:
        v = np.asarray(parts[p].vertices, dtype=np.float64)
        out.append(v[np.linspace(0, len(v) - 1, min(SAMPLE_VERTICES, len(v))).astype(int)])
    return np.concatenate(out)


def sweep_poses(joint: Joint, points: np.ndarray, count: int) -> np.ndarray:
    """[count, n, 3] ``points`` moved by ``joint`` at ``count`` values evenly over its range."""
    return np.stack([joint_motion(joint, v, points) for v in np.linspace(joint.range[0], joint.range[1], count)])


def sweep_distance(a: Joint, b: Joint, points: np.ndarray, tol: float = SAME_MOTION_TOL_NU) -> float:
    """Symmetric distance (nu) between the pose sets two joints sweep ``points`` through: the
    farthest any pose of one sweep is from the nearest pose of the other (pose distance: the
    largest vertex displacement). Unlike comparing state by state, a flipped axis over a range
    symmetric about rest, or a full turn, compares equal."""
    def dense(joint: Joint) -> int:  # enough poses that neighbours differ by at most tol / 2
        lo, hi = joint.range
        reach = float(np.max(np.linalg.norm(points - np.asarray(joint.pivot), axis=1))) if joint.type == "hinge" else 1.0
        return int(min(2048, max(SWEEP_SAMPLES, np.ceil(abs(hi - lo) * reach / (tol / 2)) + 1)))

    def directed(x: Joint, y: Joint) -> float:
        xs, ys = sweep_poses(x, points, SWEEP_SAMPLES), sweep_poses(y, points, dense(y))
        worst = 0.0
        for pose in xs:
            worst = max(worst, float(np.min(np.max(np.linalg.norm(ys - pose, axis=2), axis=1))))
        return worst

    return max(directed(a, b), directed(b, a))


def symmetric_about(points: np.ndarray, joint: Joint, tol: float = SAME_MOTION_TOL_NU, turns: int = 7) -> bool:
    """Whether ``points`` look the same (as a set, within ``tol``) after any turn about a hinge's
    axis line: a round knob or wheel turned about its own axis occupies the same space."""
    if joint.type != "hinge":
        return False
    tree = cKDTree(points)
    for angle in np.linspace(0, 2 * np.pi, turns + 2)[1:-1]:
        if tree.query(joint_motion(joint, float(angle), points))[0].max() > tol * 2:
            return False
    return True


def same_line(a: Joint, b: Joint, tol: float = SAME_MOTION_TOL_NU) -> bool:
    """Two hinge axes on one line (either direction), the pivots within ``tol`` of it."""
    u = np.asarray(a.axis, float) / np.linalg.norm(a.axis)
    v = np.asarray(b.axis, float) / np.linalg.norm(b.axis)
    d = np.asarray(b.pivot, float) - np.asarray(a.pivot, float)
    return abs(abs(u @ v) - 1) < 1e-6 and np.linalg.norm(d - (d @ u) * u) < tol
