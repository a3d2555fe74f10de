"""Rigid transforms as 4x4 numpy matrices (pure numpy)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """URDF rpy: fixed-axis rotations about X, then Y, then Z, i.e. R = Rz(yaw) Ry(pitch) Rx(roll)
    (scipy's lower-case "xyz" is that extrinsic sequence)."""
    return Rotation.from_euler("xyz", [roll, pitch, yaw]).as_matrix()


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
    """Rotation about +Z that turns an object facing ``front`` to face -Y (SPEC §2).

    Quarter turns written out with rounded cosines, so the matrix is exact (0 and +-1); a general
    rotation would leave 1e-16 residues in every imported vertex.
    """
    quarter_turns = {"-y": 0, "+x": -1, "+y": 2, "-x": 1}[front]
    angle = quarter_turns * np.pi / 2
    c, s = np.rint(np.cos(angle)), np.rint(np.sin(angle))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
