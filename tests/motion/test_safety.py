"""check_trajectory: rejects limit, speed and board violations, naming the joint or point and the time."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.kinematics import load_arm
from armlab.motion.safety import UnsafeTrajectory, check_trajectory
from armlab.motion.trajectory import plan_joint_move

ARM = load_arm("rx200")
# Arm reaching forward and down: shoulder, elbow and wrist all pitched forward.
Q_REACH_DOWN = np.array([0.0, 1.2, 0.6, 0.8, 0.0])


def _lowest_point_z(q) -> float:
    return float(np.asarray(ARM.joint_frames(q))[:, 2, 3].min())


def test_a_planned_move_between_safe_poses_passes():
    check_trajectory(ARM, plan_joint_move(ARM.sleep_rad, ARM.home_rad, ARM))
    check_trajectory(ARM, plan_joint_move(ARM.home_rad, np.array([1.0, 0.3, 0.2, 0.9, -1.0]), ARM, moving_time_s=2.0))


def test_joint_outside_its_limits_is_named_with_the_time():
    times = np.arange(5) * 0.01
    positions = np.zeros((5, 5))
    positions[3, 2] = ARM.upper_rad[2] + 0.01  # elbow beyond its upper limit at t = 0.03 s
    with pytest.raises(UnsafeTrajectory, match=r"elbow = 1\.6332 rad at t = 0\.030 s is outside its limits"):
        check_trajectory(ARM, JointTrajectory(times, positions), check_rates=False)


@pytest.mark.parametrize("joint", range(5))
@pytest.mark.parametrize("side", ["lower", "upper"])
def test_each_joint_beyond_either_limit_is_refused(joint, side):
    """Both ends of every joint's range (before, only the elbow's upper limit was tested: a check ignoring
    the lower limits passed). A sample 0.01 rad past the limit, the rest of the trajectory at rest inside."""
    name = ("waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate")[joint]
    times = np.arange(5) * 0.01
    limit = (ARM.lower_rad if side == "lower" else ARM.upper_rad)[joint]
    positions = np.tile(Q_REACH_DOWN, (5, 1))
    positions[2, joint] = limit + (-0.01 if side == "lower" else 0.01)
    with pytest.raises(UnsafeTrajectory, match=rf"{name} = {positions[2, joint]:.4f} rad at t = 0\.020 s is outside its limits"):
        check_trajectory(ARM, JointTrajectory(times, positions), check_rates=False, clearance_m=-1.0)
    positions[2, joint] = limit  # on the limit itself: allowed
    check_trajectory(ARM, JointTrajectory(times, positions), check_rates=False, clearance_m=-1.0)


def test_too_fast_and_too_sharp_are_rejected_by_finite_differences():
    times = np.arange(4) * 0.01
    jump = np.zeros((4, 5))
    jump[2:, 1] = 0.02  # shoulder: 0.02 rad in 10 ms = 2 rad/s > 1 rad/s
    with pytest.raises(UnsafeTrajectory, match=r"shoulder moves at 2\.000 rad/s at t = 0\.010 s"):
        check_trajectory(ARM, JointTrajectory(times, jump))
    ramp = np.zeros((4, 5))
    ramp[2:, 0] = [0.001, 0.002]  # waist: 0 → 0.1 rad/s within 10 ms = 10 rad/s² > 5 rad/s²
    with pytest.raises(UnsafeTrajectory, match=r"waist accelerates at 10\.000 rad/s² at t = 0\.010 s"):
        check_trajectory(ARM, JointTrajectory(times, ramp))
    check_trajectory(ARM, JointTrajectory(times, ramp), check_rates=False)  # positions alone are fine


def test_a_link_below_the_board_is_rejected():
    assert _lowest_point_z(Q_REACH_DOWN) < 0.0  # precondition: this pose puts the gripper under the board
    trajectory = plan_joint_move(ARM.home_rad, Q_REACH_DOWN, ARM)
    with pytest.raises(UnsafeTrajectory, match=r"gripper point at z = -?\d+\.\d mm at t = \d\.\d{3} s is below the board"):
        check_trajectory(ARM, trajectory)


def test_clearance_is_applied_to_every_link_point():
    # Find a pose along the same move whose lowest point is 20 mm above the board.
    move = plan_joint_move(ARM.home_rad, Q_REACH_DOWN, ARM)
    heights = np.array([_lowest_point_z(q) for q in move.positions_rad])
    index = int(np.flatnonzero(heights < 0.020)[0])
    prefix = JointTrajectory(move.times_s[:index], move.positions_rad[:index])
    assert 0.020 <= heights[:index].min() < 0.030
    check_trajectory(ARM, prefix, clearance_m=0.015)
    with pytest.raises(UnsafeTrajectory, match=r"below the board surface \+ clearance \(30\.0 mm\)"):
        check_trajectory(ARM, prefix, clearance_m=0.030)


def test_wrong_number_of_joints_is_rejected():
    with pytest.raises(UnsafeTrajectory, match="trajectory has 4 joints, the arm has 5"):
        check_trajectory(ARM, JointTrajectory(np.array([0.0, 0.01]), np.zeros((2, 4))))
