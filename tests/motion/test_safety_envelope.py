"""The safety envelope beyond joint and speed limits: the workspace box (every link point), the largest
change of a joint between two samples, and a trajectory's start at the measured joints."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.kinematics import load_arm
from armlab.motion.safety import UnsafeTrajectory, check_start, check_trajectory
from armlab.motion.trajectory import plan_joint_move
from armlab.motion_config import MotionConfig, load_motion_config

ARM = load_arm("rx200")
# Home pose turned to face world +x: the gripper point at x = 408.575 mm, z = 304.57 mm + base height.
FACING_X = np.array([-math.pi / 2, 0.0, 0.0, 0.0, 0.0])
NARROW_BOX = ((-0.30, -0.40, 0.0), (0.30, 0.60, 0.70))


def _gripper_x(q) -> float:
    return float(ARM.fk(q)[0, 3])


def test_the_configured_box_holds_the_everyday_poses():
    config = load_motion_config()
    for q in (ARM.home_rad, ARM.sleep_rad, FACING_X):
        check_trajectory(ARM, plan_joint_move(ARM.sleep_rad, q, ARM), workspace_m=config.workspace_m, max_step_rad=config.max_step_rad)


def test_leaving_the_box_is_named_with_the_point_and_the_time():
    assert abs(_gripper_x(FACING_X)) > 0.40  # the gripper point reaches past x = 0.3 m
    trajectory = plan_joint_move(ARM.home_rad, FACING_X, ARM)
    with pytest.raises(UnsafeTrajectory, match=r"gripper point at \(x = -?\d+ mm.*leaves the workspace box \[-300, -400, 0\]\.\.\[300, 600, 700\] mm"):
        check_trajectory(ARM, trajectory, workspace_m=NARROW_BOX)
    check_trajectory(ARM, trajectory)  # no box: only the limits, which it keeps


def test_a_jump_between_two_samples_is_refused_even_without_rate_checks():
    times = np.array([0.0, 1.0, 2.0])
    positions = np.zeros((3, 5))
    positions[1:, 0] = 0.3  # waist jumps 0.3 rad between two samples (slow enough for the rate check)
    with pytest.raises(UnsafeTrajectory, match=r"waist jumps 0\.300 rad between samples at t = 0\.000 s \(at most 0\.100 rad per step\)"):
        check_trajectory(ARM, JointTrajectory(times, positions), check_rates=False, max_step_rad=0.1)
    check_trajectory(ARM, JointTrajectory(times, positions), check_rates=False, max_step_rad=0.5)


def test_a_trajectory_must_start_where_the_arm_is():
    trajectory = plan_joint_move(ARM.home_rad, FACING_X, ARM)
    check_start(trajectory, ARM.home_rad + 0.01, 0.05, ARM.joint_names)
    with pytest.raises(UnsafeTrajectory, match=r"starts 0\.200 rad from where elbow is"):
        check_start(trajectory, ARM.home_rad + np.array([0, 0, 0.2, 0, 0]), 0.05, ARM.joint_names)


def test_the_box_must_be_a_box():
    with pytest.raises(ValueError, match="x must have finite min < max"):
        MotionConfig(workspace_min_m=(0.5, -0.4, 0.0), workspace_max_m=(-0.5, 0.6, 0.7))
