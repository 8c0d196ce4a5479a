"""armlab/kinematics/rotations.py against rotations known by hand (not read back from the library it wraps)."""

import math

import mujoco
import numpy as np
import pytest

from armlab.kinematics.rotations import (
    matrix_from_rpy,
    quat_wxyz_from_matrix,
    quat_wxyz_from_yaw,
    quat_xyzw_from_matrix,
    rotation_about,
    rotation_angle_rad,
    rotation_from_rotvec,
    rotation_taking,
    rpy_from_matrix,
    yaw_from_quat_wxyz,
)

QUARTER_TURN_Z = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def test_a_quarter_turn_about_z_maps_x_to_y():
    assert rotation_from_rotvec([0.0, 0.0, math.pi / 2]) == pytest.approx(QUARTER_TURN_Z, abs=1e-12)
    assert rotation_about([0.0, 0.0, 5.0], math.pi / 2) == pytest.approx(QUARTER_TURN_Z, abs=1e-12)  # the axis's length does not matter
    assert rotation_from_rotvec(np.zeros(3)) == pytest.approx(np.eye(3))


def test_many_angles_about_one_axis_give_one_matrix_each():
    turns = rotation_about([1.0, 0.0, 0.0], np.array([0.0, math.pi / 2, math.pi]))
    assert turns.shape == (3, 3, 3)
    assert turns[1] @ np.array([0.0, 1.0, 0.0]) == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)
    assert turns[2] @ np.array([0.0, 1.0, 0.0]) == pytest.approx([0.0, -1.0, 0.0], abs=1e-12)


def test_the_angle_between_two_orientations():
    assert rotation_angle_rad(np.eye(3), QUARTER_TURN_Z) == pytest.approx(math.pi / 2)
    assert rotation_angle_rad(QUARTER_TURN_Z, QUARTER_TURN_Z) == pytest.approx(0.0, abs=1e-9)
    assert rotation_angle_rad(np.eye(3), np.diag([1.0, -1.0, -1.0])) == pytest.approx(math.pi)


@pytest.mark.parametrize("direction", [[0.1, 0.0, 0.995], [0.0, -0.3, 0.9], [0.0, 0.0, 1.0], [0.6, 0.8, 0.0]])
def test_the_rotation_taking_a_direction_onto_z_is_the_smallest_one(direction):
    R = rotation_taking(direction, [0.0, 0.0, 1.0])
    unit = np.asarray(direction) / np.linalg.norm(direction)
    assert R @ unit == pytest.approx([0.0, 0.0, 1.0], abs=1e-12)
    assert rotation_angle_rad(np.eye(3), R) == pytest.approx(math.acos(unit[2]), abs=1e-9)  # no turn about z added
    assert np.linalg.det(R) == pytest.approx(1.0)


def test_quaternions_are_scalar_first_and_yaw_round_trips():
    assert quat_wxyz_from_yaw(math.pi / 2) == pytest.approx((math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)))
    q = quat_wxyz_from_matrix(QUARTER_TURN_Z)
    assert abs(float(np.dot(q, [math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)]))) == pytest.approx(1.0)  # the same up to sign
    for yaw in (-3.0, -0.4, 0.0, 1.2, 3.1):
        assert yaw_from_quat_wxyz(quat_wxyz_from_yaw(yaw)) == pytest.approx(yaw)
    pitched = quat_wxyz_from_matrix(rotation_about([0.0, 0.0, 1.0], 0.7) @ rotation_about([0.0, 1.0, 0.0], 0.3))
    assert yaw_from_quat_wxyz(pitched) == pytest.approx(0.7)  # the heading of x projected on the board


def test_recording_quaternions_are_mujocos_in_ros_order():
    """quat_xyzw_from_matrix (the recordings' /tf) against MuJoCo's own conversion, up to the sign of a quaternion."""
    rng = np.random.default_rng(3)
    for rotvec in rng.normal(size=(50, 3)) * 2.0:
        R = rotation_from_rotvec(rotvec)
        reference = np.zeros(4)
        mujoco.mju_mat2Quat(reference, R.reshape(-1))
        x, y, z, w = quat_xyzw_from_matrix(R)
        mine = np.array([w, x, y, z])
        assert min(np.abs(mine - reference).max(), np.abs(mine + reference).max()) < 1e-9


@pytest.mark.parametrize("rpy", [(0.3, -0.4, 2.0), (0.0, math.pi / 2, 0.0), (0.7, -math.pi / 2, -1.1), (math.pi, 0.2, 0.0)])
def test_urdf_roll_pitch_yaw_is_rz_ry_rx_and_round_trips_through_gimbal_lock(rpy):
    roll, pitch, yaw = rpy
    expected = rotation_about((0, 0, 1), yaw) @ rotation_about((0, 1, 0), pitch) @ rotation_about((1, 0, 0), roll)
    np.testing.assert_allclose(matrix_from_rpy(rpy), expected, atol=1e-12)
    np.testing.assert_allclose(matrix_from_rpy(rpy_from_matrix(expected)), expected, atol=1e-9)
