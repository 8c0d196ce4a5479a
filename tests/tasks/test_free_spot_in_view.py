"""A block a job puts aside stays in the camera's view while the arm waits at its look pose: beside the
parked gripper it reads occluded, and a job leaves occluded blocks where they are (sort_stack L3 seed 1
with the realistic camera left its red block at (0, 140) mm, 180 of 300 points)."""

from __future__ import annotations

import math

import numpy as np
from seen_blocks import seen_block
from test_stack_high_plan import fake_runner

from armlab import skills
from armlab.tasks.runner import TaskRunner
from armlab.vision.self_filter import RobotVolume

LARGE_EDGE_M = 0.038


def _board_with_two_holes() -> list:
    """Blocks every 50 mm over the board but in a wide hole before the parked gripper (0, 140) mm and a
    narrower one at (200, 250) mm: the farthest-from-everything spot is the one beside the gripper."""
    objects = []
    for x in np.arange(-0.35, 0.351, 0.05):
        for y in np.arange(0.0, 0.401, 0.05):
            if math.dist((x, y), (0.0, 0.14)) > 0.10 and math.dist((x, y), (0.2, 0.25)) > 0.08:
                objects.append(seen_block("red", "large", float(x), float(y), LARGE_EDGE_M))
    return objects


def test_the_spot_beside_the_parked_gripper_is_hidden_from_the_camera():
    runner = fake_runner()
    assert skills.arm_hides_block(runner.station, runner.look_pose_rad, (0.0, 0.14), LARGE_EDGE_M)
    assert not skills.arm_hides_block(runner.station, runner.look_pose_rad, (0.2, 0.25), LARGE_EDGE_M)


def test_free_spot_picks_a_spot_the_parked_arm_leaves_in_view():
    runner = fake_runner()
    spot = TaskRunner.free_spot(runner, _board_with_two_holes(), LARGE_EDGE_M)
    assert math.dist(spot, (0.2, 0.25)) < 0.04, spot  # not the wider hole before the gripper
    assert not skills.arm_hides_block(runner.station, runner.look_pose_rad, spot, LARGE_EDGE_M)


def test_a_volume_hides_what_lies_behind_it_from_the_camera():
    box = RobotVolume(np.zeros((0, 2, 3)), np.zeros(0), np.array([np.eye(4)]), np.array([[0.05, 0.05, 0.05]]))
    camera_m = (0.0, 0.0, 1.0)
    assert box.hides(camera_m, [(0.0, 0.0, -0.2)])  # straight below the box
    assert not box.hides(camera_m, [(0.3, 0.0, -0.2)])  # beside it
    assert box.hides(camera_m, [(0.3, 0.0, -0.2), (0.0, 0.02, -0.1)])  # any point hidden
