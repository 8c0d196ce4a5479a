"""The motion planners on a 6-joint arm (the UR3 kinematics model, config/arms/ur3.yaml) and a suction cup.

Truth here is forward kinematics of the arm's DH table (ArmModel.fk_dh), applied to every planned
sample: a Cartesian jog step must keep the tool's whole rotation matrix (not only pitch and yaw, as a
5-joint arm does), a pitch step must turn the tool about a horizontal axis through its point, and a
suction pick must come straight down along the cup's axis (tool x axis vertical) onto the top face
centre. The RX200's finger plans are covered, unchanged, by the other tests in this folder.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.kinematics import Unreachable, load_arm
from armlab.motion import GripperStep, TrajectoryStep, load_motion_config, plan_pick, plan_place
from armlab.motion.gripper_step import StepSpeeds, plan_gripper_step

UR3 = load_arm("ur3")
CONFIG = load_motion_config()
SPEEDS = StepSpeeds(0.05, 0.2, 0.5, 2.0)
DOWN = np.array([0.0, 0.0, -1.0])

# Start poses: the cup pointing down over the board, and tilted out of the arm's vertical plane (there a
# pitch-and-yaw planner turns the tool as the point moves sideways).
START_POSES = {
    "pointing down": np.array([0.3, -1.2, 1.3, -1.7, -1.57, 0.2]),
    "tilted sideways": np.array([0.3, -1.2, 1.3, -1.4, -1.17, 0.2]),
    "reaching out": np.array([-0.6, -0.8, 0.9, -1.8, -1.57, 0.5]),
}


def rotation_angle_deg(R_a, R_b) -> float:
    return math.degrees(math.acos(np.clip((np.trace(R_a.T @ R_b) - 1.0) / 2.0, -1.0, 1.0)))


@pytest.mark.parametrize("start", START_POSES, ids=list(START_POSES))
@pytest.mark.parametrize("axis,amount", [("x", 0.03), ("y", -0.03), ("z", 0.03), ("z", -0.03)])
def test_cartesian_step_keeps_the_full_orientation(start, axis, amount):
    q0 = START_POSES[start]
    trajectory = plan_gripper_step(UR3, q0, axis, amount, SPEEDS)
    T = UR3.fk_dh(trajectory.positions_rad)
    T0 = UR3.fk_dh(q0)
    direction = np.eye(3)["xyz".index(axis)]
    turn_deg = max(rotation_angle_deg(T0[:3, :3], pose[:3, :3]) for pose in T)
    off_line_m = max(np.linalg.norm((p - T0[:3, 3]) - ((p - T0[:3, 3]) @ direction) * direction) for p in T[:, :3, 3])
    end_m = T[-1, :3, 3] - (T0[:3, 3] + amount * direction)
    assert np.allclose(trajectory.positions_rad[0], q0)
    assert turn_deg < 0.1, f"the tool turned {turn_deg:.3f}° during a {axis} step"
    assert off_line_m < 0.001 and np.linalg.norm(end_m) < 0.0005, (off_line_m, end_m)


def test_pitch_step_turns_about_a_horizontal_axis_through_the_tool_point():
    q0 = START_POSES["tilted sideways"]
    T0 = UR3.fk_dh(q0)
    trajectory = plan_gripper_step(UR3, q0, "pitch", 0.2, SPEEDS)
    T = UR3.fk_dh(trajectory.positions_rad)
    assert np.linalg.norm(T[:, :3, 3] - T0[:3, 3], axis=1).max() < 0.001
    relative = T[-1, :3, :3] @ T0[:3, :3].T  # world-frame rotation the step made
    angle = math.acos(np.clip((np.trace(relative) - 1.0) / 2.0, -1.0, 1.0))
    axis = np.array([relative[2, 1] - relative[1, 2], relative[0, 2] - relative[2, 0], relative[1, 0] - relative[0, 1]])
    axis /= np.linalg.norm(axis)
    assert math.degrees(angle) == pytest.approx(math.degrees(0.2), abs=0.1)
    assert abs(axis[2]) < 1e-3, f"the pitch axis {axis.round(4).tolist()} is not horizontal"
    # +pitch tilts the approach (tool x) further down in the arm's vertical plane: pitch = atan2(-a_z, a · radial)
    radial = T0[:2, 3] / np.linalg.norm(T0[:2, 3])  # the UR3's base axis is the world z axis
    pitch = [math.atan2(-pose[2, 0], pose[:2, 0] @ radial) for pose in (T0, T[-1])]
    assert math.degrees(pitch[1] - pitch[0]) == pytest.approx(math.degrees(0.2), abs=0.1)


def test_step_that_cannot_keep_the_orientation_is_refused_before_anything_moves():
    q0 = START_POSES["reaching out"]
    reach = np.linalg.norm(UR3.fk_dh(q0)[:2, 3])
    outward = UR3.fk_dh(q0)[:2, 3] / reach
    axis = "x" if abs(outward[0]) > abs(outward[1]) else "y"
    sign = math.copysign(1.0, outward["xy".index(axis)])
    with pytest.raises(Unreachable):  # 100 mm further out than a 0.5 m arm reaches with this tool orientation
        for _ in range(5):
            trajectory = plan_gripper_step(UR3, q0, axis, sign * 0.1, SPEEDS)
            q0 = trajectory.positions_rad[-1]


def _trajectory_steps(steps):
    return {step.name: step.trajectory for step in steps if isinstance(step, TrajectoryStep)}


def test_suction_pick_comes_straight_down_the_cup_axis_onto_the_top_face_centre():
    top = np.array([-0.30, -0.15, 0.038])
    steps = plan_pick(UR3, START_POSES["pointing down"], top, 0.3, CONFIG, block_height_m=0.038, tool="suction")
    assert [s.action for s in steps if isinstance(s, GripperStep)] == ["release", "grasp"]  # vacuum off, then on
    moves = _trajectory_steps(steps)
    for name in ("descend to grasp", "lift"):
        T = UR3.fk_dh(moves[name].positions_rad)
        tilt_deg = np.degrees(np.arccos(np.clip(T[:, :3, 0] @ DOWN, -1.0, 1.0))).max()
        assert tilt_deg < 0.1, f"{name}: the cup axis is {tilt_deg:.2f}° off vertical"
        assert np.abs(T[:, :2, 3] - top[:2]).max() < 0.0005, f"{name}: the cup leaves the line over the top face centre"
    lowest = UR3.fk_dh(moves["descend to grasp"].positions_rad[-1])[2, 3]
    assert top[2] - 0.005 < lowest <= top[2], f"the cup stops at z = {lowest * 1000:.1f} mm: not on the top face"
    # fingers grasp lower, around the block's sides
    fingers = _trajectory_steps(plan_pick(UR3, START_POSES["pointing down"], top, 0.3, CONFIG, 0.038, tool="fingers"))
    assert UR3.fk_dh(fingers["descend to grasp"].positions_rad[-1])[2, 3] < top[2] - 0.01


def test_suction_place_lowers_the_held_block_onto_the_surface_straight_down():
    surface = np.array([-0.15, -0.30, 0.0])
    edge = 0.038
    steps = plan_place(UR3, START_POSES["pointing down"], surface, 0.0, CONFIG, edge, tool="suction")
    moves = _trajectory_steps(steps)
    T = UR3.fk_dh(moves["descend to place"].positions_rad)
    assert np.degrees(np.arccos(np.clip(T[:, :3, 0] @ DOWN, -1.0, 1.0))).max() < 0.1
    bottom_of_block = T[-1, 2, 3] + CONFIG.suction_press_m - edge  # the cup holds the top face
    assert 0.0 < bottom_of_block <= 0.01, f"released with the block's bottom {bottom_of_block * 1000:.1f} mm up"


def test_suction_never_falls_back_to_a_tilted_approach():
    # 580 mm out (beyond the 0.5 m reach pointing down) fingers still take a block tilted; a cup would not seal.
    point = np.array([0.58 * math.cos(-2.4), 0.58 * math.sin(-2.4), 0.038])
    fingers = _trajectory_steps(plan_pick(UR3, START_POSES["pointing down"], point, 0.0, CONFIG, 0.038, tool="fingers"))
    approach = UR3.fk_dh(fingers["descend to grasp"].positions_rad[-1])[:3, 0]
    assert np.degrees(np.arccos(approach @ DOWN)) > 10.0  # the premise: reachable only tilted
    with pytest.raises(Unreachable, match="suction cup"):
        plan_pick(UR3, START_POSES["pointing down"], point, 0.0, CONFIG, 0.038, tool="suction")


def test_unknown_gripper_type_is_refused():
    with pytest.raises(ValueError, match="gripper type"):
        plan_pick(UR3, START_POSES["pointing down"], [-0.3, -0.15, 0.038], 0.0, CONFIG, 0.038, tool="magnet")


def _heading_deg(T) -> float:
    return math.degrees(math.atan2(T[1, 1], T[0, 1]))


def test_a_pose_move_without_a_yaw_keeps_the_tools_heading():
    from armlab.motion.pose_path import solve_pose_move

    q0 = START_POSES["pointing down"]
    heading0 = _heading_deg(UR3.fk_dh(q0))
    target = [-0.15, -0.30, 0.12]
    q = solve_pose_move(UR3, target, None, None, q0)
    T = UR3.fk_dh(q)
    assert np.linalg.norm(T[:3, 3] - target) < 1e-4
    assert math.degrees(math.acos(np.clip(T[:3, 0] @ DOWN, -1, 1))) < 0.1  # straight down
    assert abs(math.remainder(_heading_deg(T) - heading0, 360.0)) < 0.1
    # the premise: a pitch-and-yaw solve (ArmModel.ik without a yaw) would turn the tool to another heading
    assert abs(math.remainder(_heading_deg(UR3.fk_dh(UR3.ik(target, pitch=math.pi / 2, q_seed=q0))) - heading0, 360.0)) > 5.0


def test_a_pose_move_with_a_pitch_and_a_yaw_reaches_them():
    from armlab.motion.pose_path import solve_pose_move

    target = [-0.25, -0.20, 0.15]
    T = UR3.fk_dh(solve_pose_move(UR3, target, 1.0, 0.4, START_POSES["pointing down"]))
    radial = np.asarray(target[:2]) / np.linalg.norm(target[:2])  # the UR3's base axis is the world z axis
    assert math.atan2(-T[2, 0], T[:2, 0] @ radial) == pytest.approx(1.0, abs=1e-3)  # pitch in the arm's plane
    assert abs(T[:2, 0] @ np.array([-radial[1], radial[0]])) < 1e-3  # no sideways tilt
    # the y axis: the heading 0.4 (or a quarter turn of it) made perpendicular to the approach axis
    closest = []
    for k in range(4):
        heading = np.array([math.cos(0.4 + k * math.pi / 2), math.sin(0.4 + k * math.pi / 2), 0.0])
        wanted = heading - (heading @ T[:3, 0]) * T[:3, 0]
        closest.append(math.acos(np.clip(T[:3, 1] @ wanted / np.linalg.norm(wanted), -1, 1)))
    assert min(closest) < 1e-3, np.degrees(closest)
