"""Numerical IK (Levenberg-Marquardt with limits and restarts): UR3 success rate, RX200 full poses,
generic position IK, and the Modern Robotics Jacobian it is built on."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armlab.kinematics import Unreachable
from armlab.kinematics.ik_numeric import rotation_error
from armlab.kinematics.screws import fk_space, jacobian_space, matrix_exp6, matrix_log6, se3_to_vec, vec_to_se3


def pose_errors(T_a, T_b):
    position = np.linalg.norm(T_a[:3, 3] - T_b[:3, 3])
    cos_angle = np.clip((np.trace(T_a[:3, :3].T @ T_b[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)
    return position, math.degrees(math.acos(cos_angle))


def reachable_poses(arm, count, seed):
    """FK poses of random in-limit joints with every joint frame above the board."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(count * 3, arm.dof))
    above = np.all(arm.joint_frames(q)[:, :, 2, 3] >= 0.0, axis=1)
    return arm.fk(q[above][:count])


def test_ur3_solves_random_reachable_poses(ur3):
    poses = reachable_poses(ur3, 1000, seed=21)
    assert len(poses) == 1000
    solved = 0
    for target in poses:
        try:
            q = ur3.ik_pose(target)
        except Unreachable:
            continue
        position_m, angle_deg = pose_errors(ur3.fk(q), target)
        assert position_m <= 1e-4 and angle_deg <= 0.1  # a returned solution always meets the tolerance
        assert ur3.within_limits(q)
        solved += 1
    assert solved / len(poses) >= 0.995


def test_rx200_full_pose_ik_from_fk(rx200):
    for target in reachable_poses(rx200, 100, seed=22):
        q = rx200.ik_pose(target)
        position_m, angle_deg = pose_errors(rx200.fk(q), target)
        assert position_m <= 1e-4 and angle_deg <= 0.1


def test_seed_near_the_answer_converges_to_the_nearby_solution(ur3):
    q_true = np.array([0.3, -1.2, 1.1, -1.4, -1.5, 0.2])
    q = ur3.ik_pose(ur3.fk(q_true), q_seed=q_true + 0.05)
    assert np.allclose(q, q_true, atol=1e-4)


def test_unreachable_pose_raises_with_the_residual(ur3, rx200):
    far = np.eye(4)
    far[:3, 3] = [0.9, 0.0, 0.2]
    with pytest.raises(Unreachable, match="out of reach") as error:
        ur3.ik_pose(far)
    assert error.value.reason == "out of reach" and "mm" in str(error.value)
    # a 5-joint arm keeps its approach axis in the vertical plane through the base axis and the
    # gripper: pointing sideways (tangentially) at a reachable position is impossible
    tangential = np.array([-0.25, 0.1, 0.0]) / np.hypot(0.25, 0.1)
    up = np.array([0.0, 0.0, 1.0])
    sideways = np.eye(4)
    sideways[:3, :3] = np.column_stack([tangential, np.cross(up, tangential), up])
    sideways[:3, 3] = [0.1, 0.25, 0.15]
    rx200.ik([0.1, 0.25, 0.15])  # the position alone is reachable
    with pytest.raises(Unreachable, match="out of reach"):
        rx200.ik_pose(sideways)
    below = np.eye(4)
    below[2, 3] = -0.05
    with pytest.raises(Unreachable, match="below the table"):
        ur3.ik_pose(below)


@pytest.mark.parametrize("bad", [np.eye(3), np.full((4, 4), np.nan), np.diag([2.0, 1.0, 1.0, 1.0])])
def test_ik_pose_rejects_malformed_targets(ur3, bad):
    with pytest.raises(ValueError) as error:
        ur3.ik_pose(bad)
    assert not isinstance(error.value, Unreachable)


def test_generic_position_ik_points_down_and_aligns_yaw(ur3):
    q, pitch = ur3.ik_with_pitch([0.3, 0.1, 0.05], yaw=0.4)
    pose = ur3.fk(q)
    assert pitch == pytest.approx(math.pi / 2)
    assert np.allclose(pose[:3, 3], [0.3, 0.1, 0.05], atol=1e-4)
    assert np.allclose(pose[:3, 0], [0, 0, -1], atol=1e-3)
    finger = pose[:3, 1]
    angle = math.atan2(finger[1], finger[0]) - 0.4
    assert abs((angle + math.pi / 4) % (math.pi / 2) - math.pi / 4) < 2e-3
    with pytest.raises(Unreachable, match="out of reach"):
        ur3.ik([0.8, 0.0, 0.1])


def test_generic_batch_ik_reports_failures(ur3):
    q, ok = ur3.ik_batch([[0.3, 0.1, 0.05], [0.9, 0.0, 0.1]], pitch=math.pi / 2)
    assert ok.tolist() == [True, False]
    assert np.isnan(q[1]).all() and np.allclose(ur3.fk(q[0])[:3, 3], [0.3, 0.1, 0.05], atol=1e-4)


def test_rotation_error_is_the_rotation_vector():
    for axis, angle in (([0, 0, 1.0], 0.3), ([1, 1, 0.0], 2.0), ([0, 1, 0.0], math.pi - 1e-9), ([1, 0, 0.0], 0.0)):
        axis = np.asarray(axis) / np.linalg.norm(axis)
        rotation = matrix_exp6(vec_to_se3(np.concatenate([axis * angle, np.zeros(3)])))
        target = tuple(np.concatenate([rotation[:3, :3], np.zeros((3, 1))], axis=1).reshape(-1))
        identity = tuple(np.eye(3, 4).reshape(-1))
        assert np.allclose(np.abs(rotation_error(target, identity)), np.abs(axis * angle), atol=1e-6)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-3.0, 3.0), min_size=5, max_size=5))
def test_space_jacobian_matches_finite_differences(rx200, q_list):
    home, axes = np.asarray(rx200.config.pox.M), np.asarray(rx200.config.pox.screw_axes)
    q = np.array(q_list)
    jacobian = jacobian_space(axes, q)
    step = 1e-6
    for i in range(5):
        dq = np.zeros(5)
        dq[i] = step
        delta = fk_space(home, axes, q + dq) @ np.linalg.inv(fk_space(home, axes, q - dq))
        twist = se3_to_vec(matrix_log6(delta)) / (2 * step)
        assert np.allclose(twist, jacobian[:, i], atol=1e-5)


def test_batch_pose_ik_solves_ur3_and_rx200_poses(ur3, rx200):
    for arm, count in ((ur3, 2000), (rx200, 1000)):
        poses = reachable_poses(arm, count, seed=23)
        q, ok = arm.ik_pose_batch(poses)
        assert ok.mean() >= 0.995, (arm.name, ok.mean())
        reached = arm.fk(q[ok])
        for T_reached, T_target in zip(reached, poses[ok]):
            position_m, angle_deg = pose_errors(T_reached, T_target)
            assert position_m <= 1e-4 and angle_deg <= 0.1
        assert arm.within_limits(q[ok]) and np.isnan(q[~ok]).all()


def test_batch_pose_ik_reports_impossible_rows(ur3):
    poses = reachable_poses(ur3, 3, seed=24)
    far = np.eye(4)
    far[:3, 3] = [0.9, 0.0, 0.2]
    below = np.eye(4)
    below[2, 3] = -0.05
    q, ok = ur3.ik_pose_batch(np.concatenate([poses, far[None], below[None]]), q_seed=ur3.home_rad)
    assert ok.tolist() == [True, True, True, False, False]
    with pytest.raises(ValueError, match="N, 4, 4"):
        ur3.ik_pose_batch(np.eye(4))
