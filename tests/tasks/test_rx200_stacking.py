"""sort_by_tag and stack_here on the default RX200 workcell (issue 12: >= 95 % over 20 seeds), the three
causes of their failures pinned:

- a large block set top-down onto a three-block column at place 1 (-300, -100) mm, the edge of the RX200's
  reach: the release point is reachable straight down but not the usual approach point 80-118 mm above it
  (the plan used to refuse: "reachable only at 80 deg pitch"); the plan now comes down a shorter way, top-down;
- a column whose top is outside the camera image (six blocks at stack_here's (-150, -120) mm) hides its own
  base: the look measures nothing there, not even the board, and the column keeps what was put on it (it
  used to read 0 mm, and the next block was set down through the column, knocking it over);
- the headless episodes that failed for these causes and for a block the parked arm hid (sort_by_tag L3
  seed 8: a block at (-41, 125) mm was never seen) now score full points on the simulation's ground truth.
Places and sizes are written out here, not read from the code."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from seen_blocks import seen_block

from armlab.kinematics import load_arm
from armlab.motion import TrajectoryStep
from armlab.motion_config import load_motion_config
from armlab.skills.manipulate import plan_place
from armlab.tasks.columns import Column

ARM = load_arm("rx200")
LARGE_M, SMALL_M = 0.038, 0.025
PLACE_1_M = (-0.300, -0.100)  # config/workcells/rx200_armlab.yaml places_m 1


def planner(q_start):
    """What the skills need from a station: the arm model, the motion config and the joints."""
    return SimpleNamespace(model=ARM, motion_config=load_motion_config(), joints_rad=lambda: np.asarray(q_start, float))


def test_a_large_block_goes_top_down_onto_a_three_block_column_at_the_edge_of_reach():
    top_m = (PLACE_1_M[0] - 0.005, PLACE_1_M[1] - 0.001, 3 * LARGE_M)  # where a real column's top stood (seed 2)
    q_start = ARM.ik([0.10, 0.20, 0.20], pitch=math.pi / 2, yaw=0.0)  # just after a pick, holding the block
    steps = plan_place(planner(q_start), top_m, 0.0, LARGE_M, [], q_start=q_start)
    descend = next(s for s in steps if isinstance(s, TrajectoryStep) and s.name == "descend to place")
    for q in descend.trajectory.positions_rad:
        T = ARM.fk(q)
        down = math.degrees(math.acos(float(np.clip(-T[2, 0], -1.0, 1.0))))  # the gripper's approach axis from straight down
        assert down <= 5.0 + 1e-6
        assert math.dist(T[:2, 3], top_m[:2]) < 0.002
    end_z_m = ARM.fk(descend.trajectory.positions_rad[-1])[2, 3]
    assert top_m[2] < end_z_m < top_m[2] + LARGE_M  # the held block's bottom just above the column's top


def block(color, size, x, y, z_top):
    return seen_block(color, size, x, y, z_top)


def test_a_column_the_camera_cannot_measure_keeps_what_was_put_on_it():
    column = Column("stack", (-0.15, -0.12))
    for color, size, edge in (("red", "large", LARGE_M), ("blue", "large", LARGE_M), ("green", "large", LARGE_M),
                              ("red", "small", SMALL_M), ("blue", "small", SMALL_M)):
        column.add(block(color, size, 0.1, 0.2, edge), edge)
    column.observe([], lambda xy: None)  # neither its top nor the board seen there
    assert column.height == 5
    assert column.surface_m() == pytest.approx((-0.15, -0.12, 3 * LARGE_M + 2 * SMALL_M))
    obstacle = column.stand_in()  # what the job's moves must keep clear of
    assert obstacle is not None and not obstacle.is_cube
    assert obstacle.position_m == pytest.approx([-0.15, -0.12, 3 * LARGE_M + 2 * SMALL_M])
    column.observe([], lambda xy: 0.0)  # the board seen there: the column is gone
    assert column.height == 0 and column.surface_m() == (-0.15, -0.12, 0.0) and column.stand_in() is None


@pytest.mark.parametrize("event, level, seed", [("stack_here", None, 11), ("sort_by_tag", 3, 8)])
def test_the_episodes_that_failed_score_full_points(event, level, seed):
    """stack_here seed 11 builds six blocks at (-150, -120) mm (it scored 1/6: the sixth went through the
    unmeasured column); sort_by_tag L3 seed 8 (7/8: a block hidden by the parked arm was left)."""
    from armlab.tasks.episode import run_episode

    run = run_episode(event, level, seed)
    assert run["points"] == run["max_points"] and run["max_points"] == {"stack_here": 6, "sort_by_tag": 8}[event], run["failures"]
