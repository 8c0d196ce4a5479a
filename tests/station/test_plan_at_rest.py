"""A plan is made from the arm at rest (issue 22 item 2): the moment the arm has stopped (the simulated servos
settled, is_moving() false) a plan_only is answered, not refused as 'while the arm moves' (CI 2026-12-04: the
station still held the finished motion's last sample period as running); a motion sent but still under way is
refused. Fast simulation: the physics advances only when the test waits, so the moment is exact."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.errors import ArmMoving

START_RAD = [0.3, 0.0, 0.3, 0.9, 0.0]
GOAL_RAD = [0.5, 0.1, 0.2, 0.8, 0.0]


def test_a_plan_is_answered_the_moment_the_arm_has_stopped(fast):
    station, cell = fast
    station.move_joints(START_RAD, moving_time_s=1.0)
    assert cell.arm.is_moving()
    with pytest.raises(ArmMoving, match="at rest"):
        station.plan_only("move_joints", q_goal_rad=GOAL_RAD)
    assert cell.wait_for(lambda: not cell.arm.is_moving(), 10.0)  # the first control tick at which it is settled
    plan = station.plan_only("move_joints", q_goal_rad=GOAL_RAD)
    assert np.allclose(plan["q_rad"][-1], GOAL_RAD, atol=1e-9)
    assert np.abs(np.asarray(plan["q_rad"][0]) - np.asarray(START_RAD)).max() < station.motion_config.start_tolerance_rad


def test_a_plan_overtaken_by_a_move_is_stale_even_while_that_move_ends(fast):
    """A plan made, then another move commanded (ending within the start tolerance of the plan's start, so the
    measured joints alone do not tell): executed while that move's last, still samples run on the station's clock
    (a fresh-clone run at load 12-20 hit it), it is stale (409 'arm_commanded'), not a 422 about the handover."""
    from armlab.errors import PlanStale

    station, cell = fast
    station.move_joints(START_RAD, moving_time_s=1.0)
    assert cell.wait_for(lambda: not cell.arm.is_moving(), 10.0)
    plan = station.plan_only("move_joints", q_goal_rad=GOAL_RAD)
    nearby = np.asarray(START_RAD) + [0.0, 0.0, 0.0, 0.03, 0.0]  # within start_tolerance_rad (0.05) of the plan's start
    station.move_joints(nearby, moving_time_s=1.0)
    trajectory, started_s = station.gate.commanded[:2]
    ends_s = started_s + trajectory.duration_s
    assert cell.wait_for(lambda: station.clock_s() >= ends_s - 0.5 * station.motion_config.handover_lead_s, 10.0)
    assert station.clock_s() < ends_s  # the move still runs on the station's clock (its last, still samples)
    with pytest.raises(PlanStale) as stale:
        station.execute_plan(plan["plan_id"])
    assert stale.value.reason in ("arm_commanded", "arm_moved"), stale.value
