"""Vertical segments, pick/place plans and move-to-pose on the real rx200 kinematics model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armlab.config import validate_config
from armlab.errors import ConfigError
from armlab.kinematics import Unreachable, load_arm
from armlab.motion.cartesian import gripper_pitch_rad, gripper_position_m, plan_vertical_segment
from armlab.motion.pick_place import GripperStep, TrajectoryStep, plan_move_to_pose, plan_pick, plan_place
from armlab.motion.safety import check_trajectory
from armlab.motion_config import MotionConfig, load_motion_config

ARM = load_arm("rx200")
CONFIG = load_motion_config()


def _tip(q) -> np.ndarray:
    return gripper_position_m(ARM, q)


def test_vertical_segment_is_a_straight_vertical_line_at_fixed_orientation():
    q_start = ARM.ik(np.array([0.05, 0.25, 0.15]), pitch=math.pi / 2, yaw=0.3, q_seed=ARM.home_rad)
    trajectory = plan_vertical_segment(ARM, q_start, 0.03, pitch_rad=math.pi / 2, yaw_rad=0.3, speed_m_s=0.1, accel_m_s2=0.4)
    tips = np.array([_tip(q) for q in trajectory.positions_rad])
    np.testing.assert_allclose(tips[:, :2], np.repeat(tips[:1, :2], len(tips), axis=0), atol=2e-4)  # x, y fixed
    assert abs(tips[-1, 2] - 0.03) < 5e-4 and abs(tips[0, 2] - 0.15) < 5e-4
    assert np.all(np.diff(tips[:, 2]) <= 1e-9)  # only ever goes down
    pitches = [gripper_pitch_rad(ARM, q) for q in trajectory.positions_rad]
    np.testing.assert_allclose(pitches, math.pi / 2, atol=1e-3)
    assert np.ptp(trajectory.positions_rad[:, 4]) < 1e-6  # wrist_rotate holds the block's yaw
    speed = np.abs(np.diff(tips[:, 2]) / np.diff(trajectory.times_s))
    assert speed.max() <= 0.1 * (1 + 1e-3) and speed.max() > 0.09  # cruises at the configured speed
    assert np.diff(trajectory.times_s).max() <= 0.01 + 1e-12
    check_trajectory(ARM, trajectory, clearance_m=0.01)


def test_pick_plan_opens_goes_above_down_grasps_and_lifts():
    top = np.array([0.10, 0.20, 0.038])  # a large block's top face
    steps = plan_pick(ARM, ARM.sleep_rad, top, 0.4, CONFIG)
    assert [type(step) for step in steps] == [GripperStep, TrajectoryStep, TrajectoryStep, GripperStep, TrajectoryStep]
    assert [step.action for step in steps if isinstance(step, GripperStep)] == ["release", "grasp"]
    move_above, descend, lift = (step for step in steps if isinstance(step, TrajectoryStep))
    grasp_z = top[2] - CONFIG.grasp_depth_m
    np.testing.assert_allclose(move_above.trajectory.positions_rad[0], ARM.sleep_rad)
    np.testing.assert_allclose(_tip(move_above.q_end_rad), [top[0], top[1], grasp_z + CONFIG.approach_height_m], atol=1e-3)
    np.testing.assert_allclose(descend.trajectory.positions_rad[0], move_above.q_end_rad)  # continuous
    np.testing.assert_allclose(_tip(descend.q_end_rad), [top[0], top[1], grasp_z], atol=1e-3)
    np.testing.assert_allclose(lift.trajectory.positions_rad[0], descend.q_end_rad)
    np.testing.assert_allclose(_tip(lift.q_end_rad), [top[0], top[1], grasp_z + CONFIG.lift_height_m], atol=1e-3)
    assert abs(gripper_pitch_rad(ARM, descend.q_end_rad) - math.pi / 2) < 1e-3  # top-down when reachable
    for step in (move_above, descend, lift):
        check_trajectory(ARM, step.trajectory, clearance_m=CONFIG.board_clearance_m)


def test_far_block_is_picked_at_a_shallower_pitch_with_straight_segments():
    top = np.array([-0.30, 0.30, 0.025])  # 424 mm out: top-down is out of reach
    with pytest.raises(Unreachable):
        ARM.ik(top - [0, 0, CONFIG.grasp_depth_m], pitch=math.pi / 2, yaw=0.0, q_seed=ARM.home_rad)
    steps = plan_pick(ARM, ARM.home_rad, top, 0.0, CONFIG)
    descend = [step for step in steps if isinstance(step, TrajectoryStep)][1]
    pitches = [gripper_pitch_rad(ARM, q) for q in descend.trajectory.positions_rad]
    assert pitches[0] < math.pi / 2 - 0.05 and np.ptp(pitches) < 1e-3
    np.testing.assert_allclose(_tip(descend.q_end_rad), top - [0, 0, CONFIG.grasp_depth_m], atol=1e-3)


def test_place_releases_the_block_just_above_the_surface():
    surface = np.array([-0.15, 0.10, 0.038])  # on top of a large block
    steps = plan_place(ARM, ARM.home_rad, surface, -0.2, CONFIG, block_height_m=0.025)
    assert [getattr(step, "action", None) for step in steps] == [None, None, "release", None]
    descend = steps[1]
    # plan_pick grasps a 25 mm block grasp_depth_m below its top unless the pads (reaching pad_reach_m
    # below the gripper point) would touch what it stands on: 15 mm with the shipped config (25 - 9 = 16).
    held_below_top = min(CONFIG.grasp_depth_m, 0.025 - CONFIG.pad_reach_m)
    assert held_below_top == pytest.approx(0.015)
    expected_z = surface[2] + 0.025 - held_below_top + CONFIG.place_clearance_m
    np.testing.assert_allclose(_tip(descend.q_end_rad), [surface[0], surface[1], expected_z], atol=1e-3)
    np.testing.assert_allclose(_tip(steps[3].q_end_rad)[2], expected_z + CONFIG.lift_height_m, atol=1e-3)


def test_unreachable_and_bad_targets_are_refused():
    with pytest.raises(Unreachable):
        plan_pick(ARM, ARM.home_rad, np.array([0.0, 1.5, 0.02]), 0.0, CONFIG)
    with pytest.raises(ValueError, match="position_m must be 3 finite"):
        plan_pick(ARM, ARM.home_rad, np.array([0.1, np.nan, 0.02]), 0.0, CONFIG)
    with pytest.raises(ValueError, match="yaw_rad must be finite"):
        plan_pick(ARM, ARM.home_rad, np.array([0.1, 0.2, 0.02]), math.inf, CONFIG)
    with pytest.raises(ValueError, match="block_height_m must be > 0"):
        plan_place(ARM, ARM.home_rad, np.array([0.1, 0.2, 0.0]), 0.0, CONFIG, block_height_m=0.0)


def test_move_to_pose_reaches_the_pose_within_limits():
    target = np.array([0.0, 0.30, 0.20])
    trajectory = plan_move_to_pose(ARM, ARM.home_rad, target, pitch_rad=0.5, yaw_rad=0.0)
    np.testing.assert_allclose(_tip(trajectory.positions_rad[-1]), target, atol=1e-3)
    assert abs(gripper_pitch_rad(ARM, trajectory.positions_rad[-1]) - 0.5) < 1e-3
    with pytest.raises(Unreachable):
        plan_move_to_pose(ARM, ARM.home_rad, np.array([0.0, 0.9, 0.2]), pitch_rad=0.0)


def test_motion_config_validation():
    assert CONFIG.approach_height_m > CONFIG.grasp_depth_m and CONFIG.sample_rate_hz >= 100
    for data, field in [
        ({"approach_height_m": -0.01}, "approach_height_m"),
        ({"sample_rate_hz": 50}, "sample_rate_hz"),
        ({"grasp_depth_m": float("nan")}, "grasp_depth_m"),
        ({"move_time_s": 1.0, "accel_time_s": 0.8}, "accel_time_s"),
        ({"approach_hieght_m": 0.1}, "approach_hieght_m"),
    ]:
        with pytest.raises(ConfigError, match=field):
            validate_config(data, MotionConfig, "motion.yaml")


@settings(max_examples=25, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(
    radius_m=st.floats(0.10, 0.50),
    bearing_rad=st.floats(-math.pi, math.pi),
    top_z_m=st.sampled_from([0.025, 0.038, 0.063, 0.076]),
    yaw_rad=st.floats(-math.pi, math.pi),
)
def test_every_pick_plan_is_reachable_continuous_and_within_limits(radius_m, bearing_rad, top_z_m, yaw_rad):
    top = np.array([radius_m * math.sin(bearing_rad), radius_m * math.cos(bearing_rad), top_z_m])
    try:
        steps = plan_pick(ARM, ARM.sleep_rad, top, yaw_rad, CONFIG)
    except Unreachable:
        assert radius_m > 0.30  # everything nearer is within reach at some pitch
        return
    trajectories = [step.trajectory for step in steps if isinstance(step, TrajectoryStep)]
    q_previous = ARM.sleep_rad
    for trajectory in trajectories:
        np.testing.assert_allclose(trajectory.positions_rad[0], q_previous, atol=1e-9)  # no jumps between steps
        check_trajectory(ARM, trajectory, clearance_m=CONFIG.board_clearance_m)  # limits, rates, board
        q_previous = trajectory.positions_rad[-1]
    grasp = top - [0.0, 0.0, CONFIG.grasp_depth_m]
    np.testing.assert_allclose(_tip(trajectories[1].positions_rad[-1]), grasp, atol=1e-3)
    descent_xy = np.array([_tip(q)[:2] for q in trajectories[1].positions_rad])
    assert np.abs(descent_xy - grasp[:2]).max() < 5e-4  # straight down


def test_grasp_keeps_the_pads_clear_of_what_a_short_block_stands_on():
    top = np.array([0.05, 0.22, 0.020])  # a 20 mm block: 15 mm deep would put the pads' ends 4 mm into the board
    steps = plan_pick(ARM, ARM.home_rad, top, 0.0, CONFIG, block_height_m=0.020)
    np.testing.assert_allclose(_tip(steps[2].q_end_rad), [0.05, 0.22, CONFIG.pad_reach_m], atol=1e-3)
    with pytest.raises(ValueError, match="block_height_m must be > 0"):
        plan_pick(ARM, ARM.home_rad, top, 0.0, CONFIG, block_height_m=-0.02)


def test_a_segment_that_would_jump_between_ik_solutions_is_refused():
    from armlab.motion.cartesian import DiscontinuousPath

    q_start = ARM.ik(np.array([0.0, 0.25, 0.10]), pitch=math.pi / 2, yaw=0.0, q_seed=ARM.home_rad)
    # The start pose's wrist matches yaw 0; asking for yaw 0.8 would snap the wrist by ≥ 0.77 rad.
    with pytest.raises(DiscontinuousPath, match=r"wrist_rotate jumps 0\.\d+ rad at z = 10\d\.\d mm"):
        plan_vertical_segment(ARM, q_start, 0.05, pitch_rad=math.pi / 2, yaw_rad=0.8)
    with pytest.raises(ValueError, match="z_goal_m must be finite"):
        plan_vertical_segment(ARM, q_start, math.nan)
