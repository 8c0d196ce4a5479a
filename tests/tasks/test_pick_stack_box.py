"""pick_stack's gripper box (DESIGN §7: the level bonus is lost if the gripper point ever leaves abs(x) <=
260 mm, -35 <= y <= 285 mm, z <= 300 mm): the planned pick and place keep every sample of their
gripper path inside it, near the box's far edge (y = 275 mm) and at the columns beside its corners.
Checked on the sampled trajectories with the box written out here (not read from the code)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion import TrajectoryStep, plan_joint_move
from armlab.motion_config import load_motion_config
from armlab.skills.manipulate import plan_pick, plan_place
from armlab.tasks import pick_stack

ARM = load_arm("rx200")
JUDGE_BOX_MIN_M = np.array([-0.260, -0.035, -np.inf])
JUDGE_BOX_MAX_M = np.array([0.260, 0.285, 0.300])
LARGE_M = 0.038


def gripper_points_m(trajectories) -> np.ndarray:
    q = np.vstack([t.positions_rad for t in trajectories])
    return np.asarray(ARM.joint_frames(q))[:, -1, :3, 3]


def outside_judge_box(points_m) -> np.ndarray:
    return np.any((points_m < JUDGE_BOX_MIN_M) | (points_m > JUDGE_BOX_MAX_M), axis=1)


def planner(q_start):
    """What the skills need from a station: the arm model, the motion config and the joints."""
    return SimpleNamespace(model=ARM, motion_config=load_motion_config(), joints_rad=lambda: np.asarray(q_start, float))


def over(x, y, z):
    return ARM.ik([x, y, z], pitch=math.pi / 2, yaw=0.0)


def test_a_plain_joint_move_between_two_blocks_near_the_far_edge_leaves_the_box():
    """The hazard itself: the joint-space sweep between two spots near y = 275 mm bulges past y = 285 mm."""
    move = plan_joint_move(over(0.20, 0.25, 0.15), over(-0.20, 0.25, 0.15), ARM)
    points = gripper_points_m([move])
    assert not outside_judge_box(points[[0, -1]]).any()
    assert outside_judge_box(points).any() and points[:, 1].max() > 0.30


@pytest.mark.parametrize("start, block", [
    ((0.20, 0.25, 0.15), (-0.20, 0.255, LARGE_M)),  # across the far edge, y near 275 mm
    ((0.21, 0.237, 0.19), (0.08, 0.27, LARGE_M)),
])
def test_a_pick_near_the_far_edge_keeps_the_whole_gripper_path_inside_the_box(start, block):
    q_start = over(*start)
    steps = plan_pick(planner(q_start), block, 0.0, LARGE_M, [], q_start=q_start,
                      max_transfer_z_m=pick_stack.GRIPPER_CEILING_M, gripper_box=pick_stack.planning_box())
    trajectories = [s.trajectory for s in steps if isinstance(s, TrajectoryStep)]
    points = gripper_points_m(trajectories)
    assert not outside_judge_box(points).any(), points[outside_judge_box(points)][:3]
    assert np.allclose(trajectories[0].positions_rad[0], q_start)
    grasp = ARM.fk(trajectories[-1].positions_rad[0])[:3, 3]  # the lift starts at the grasp point
    assert math.dist(grasp[:2], block[:2]) < 1e-3


def test_placing_on_a_column_beside_a_box_corner_keeps_the_gripper_inside():
    """The column base by its tag (250, -25) mm: a place on it from over a block at (211, 237) mm (where a
    joint move swept out to x = 272 mm) stays inside, and the base is within the judge's 30 mm of the tag."""
    base = pick_stack.column_base((0.250, -0.025), pick_stack.planning_box())
    assert math.dist(base, (0.250, -0.025)) < 0.030
    q_start = over(0.211, 0.237, 0.19)
    steps = plan_place(planner(q_start), (*base, 2 * LARGE_M), 0.0, LARGE_M, [], q_start=q_start,
                       max_transfer_z_m=pick_stack.GRIPPER_CEILING_M, gripper_box=pick_stack.planning_box())
    points = gripper_points_m([s.trajectory for s in steps if isinstance(s, TrajectoryStep)])
    assert not outside_judge_box(points).any(), points[outside_judge_box(points)][:3]
    assert plan_joint_move(q_start, steps[0].trajectory.positions_rad[-1], ARM) is not None
