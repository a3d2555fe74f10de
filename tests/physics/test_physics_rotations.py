"""The plain rotations behind the checks and importers (scipy's Rotation): right-handed, about the
right pivot, in the order each format defines."""

from __future__ import annotations

import math

import numpy as np
import pytest

from data_pipeline.importers.frames import rpy_matrix
from jax3dc.physics.dynamics import _tilt
from jax3dc.physics.kinematics import joint_motion
from jax3dc.export.blender import axis_to_z_rotation
from jax3dc.structure.schema import Joint


def test_hinge_turns_right_handed_about_its_pivot():
    hinge = Joint("hinge", (0.0, 0.0, 2.0), (1.0, 0.0, 0.0), (0.0, math.pi))  # axis not unit length
    moved = joint_motion(hinge, math.pi / 2, np.array([[2.0, 0.0, 5.0], [1.0, 0.0, 0.0]]))
    assert np.allclose(moved, [[1.0, 1.0, 5.0], [1.0, 0.0, 0.0]], atol=1e-12)
    slide = Joint("slide", (0.0, 3.0, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0))
    assert np.allclose(joint_motion(slide, 0.5, np.zeros((1, 3))), [[0.0, 0.5, 0.0]])


def test_urdf_rpy_is_fixed_axis_x_then_y_then_z():
    """R = Rz(yaw) Ry(pitch) Rx(roll): composing the single-axis turns in that order gives the same."""
    roll, pitch, yaw = 0.3, -1.1, 2.0
    composed = rpy_matrix(0, 0, yaw) @ rpy_matrix(0, pitch, 0) @ rpy_matrix(roll, 0, 0)
    assert np.allclose(rpy_matrix(roll, pitch, yaw), composed, atol=1e-12)
    assert not np.allclose(rpy_matrix(roll, pitch, yaw), rpy_matrix(roll, 0, 0) @ rpy_matrix(0, pitch, 0)
                           @ rpy_matrix(0, 0, yaw), atol=1e-3)  # the other order is a different frame
    assert np.allclose(rpy_matrix(0, 0, math.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    assert np.allclose(rpy_matrix(math.pi / 2, 0, 0) @ [0, 1, 0], [0, 0, 1], atol=1e-12)


@pytest.mark.parametrize("angle", [0.0, 0.4, 2.5])
def test_tilt_of_a_mujoco_quaternion(angle):
    quat = 3.0 * np.array([math.cos(angle / 2), 0.0, math.sin(angle / 2), 0.0])  # about y, not normalised
    assert _tilt(quat) == pytest.approx(angle, abs=1e-7)


def test_axis_frame_takes_z_to_the_axis_by_the_smallest_turn():
    rng = np.random.default_rng(0)
    z = np.array([0.0, 0.0, 1.0])
    for axis in [*rng.normal(size=(20, 3)), [0, 0, 1], [1, 0, 0], [0, 0, -1]]:
        axis = np.asarray(axis, float) / np.linalg.norm(axis)
        r = axis_to_z_rotation(axis)[:3, :3]
        assert np.allclose(r @ z, axis, atol=1e-12)
        assert np.allclose(r.T @ r, np.eye(3), atol=1e-12) and np.linalg.det(r) == pytest.approx(1.0)
        turn = math.acos(np.clip((np.trace(r) - 1) / 2, -1, 1))
        assert turn == pytest.approx(math.acos(np.clip(axis[2], -1, 1)), abs=1e-7)  # no extra twist
    assert np.array_equal(axis_to_z_rotation(-z)[:3, :3], np.diag([1.0, -1.0, -1.0]))
