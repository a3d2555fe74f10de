"""Rigid transforms as 4x4 numpy matrices (pure numpy)."""

from __future__ import annotations

import numpy as np


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF rpy: fixed-axis rotations about X, then Y, then Z, i.e. R = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def pose(rotation: np.ndarray, translation) -> np.ndarray:
    """Homogeneous 4x4 transform from a 3x3 rotation and a translation."""
    t = np.eye(4)
    t[:3, :3] = rotation
    t[:3, 3] = np.asarray(translation, dtype=float)
    return t


def scaling(factors) -> np.ndarray:
    return np.diag([*np.asarray(factors, dtype=float), 1.0])


FRONTS = ("-y", "+y", "-x", "+x")


def front_to_minus_y(front: str) -> np.ndarray:
    """Rotation about +Z that turns an object facing ``front`` to face -Y (SPEC §2)."""
    quarter_turns = {"-y": 0, "+x": -1, "+y": 2, "-x": 1}[front]
    angle = quarter_turns * np.pi / 2
    c, s = np.rint(np.cos(angle)), np.rint(np.sin(angle))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
