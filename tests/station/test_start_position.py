"""Where a motion from rest starts when the one before is in its last ticks: where the command comes to rest, not
the measured joints. bench/motion_continuity (speed changes during repeats, 1.05x the acceleration limit once) showed
a repeat's next run planned from the measured shoulder 4 ms before the run before it ended: the measured joint trails
the command by the servos' lag, so the command stepped 1.9 mrad in one 4 ms tick. Fast synchronous simulation."""

from __future__ import annotations

import numpy as np

from armlab.motion.handover import sample_positions

GOAL_Q = np.array([0.4, 0.3, 0.2, -0.3, 0.2])


def test_a_motion_in_its_last_ticks_starts_the_next_where_the_command_rests(fast):
    station, cell = fast
    station.home(wait=True)
    station.move_joints(GOAL_Q, moving_time_s=1.0)
    with station._lock:
        trajectory, started_s, _ = station.gate.commanded
    end_s = started_s + trajectory.duration_s
    cell.step(end_s - 0.006 - station.clock_s())  # inside its last sample period, still moving slowly
    assert station.clock_s() < end_s
    commanded_now = sample_positions(trajectory, np.array([station.clock_s() - started_s]))[0]
    measured = station.joints_rad()
    # the servos' lag: the two differ (~0.007 mrad here since the ideal servos follow their trajectory at every physics
    # step, ~0.07 mrad with the acceleration fed forward once per control tick; the start must still be the command's
    # end to the nanoradian below, not the measured joints)
    assert np.max(np.abs(measured - commanded_now)) > 2e-6
    start = station.start_position()
    assert np.allclose(start, trajectory.positions_rad[-1], atol=1e-9), (start - trajectory.positions_rad[-1], measured)
    station.wait_motion(5.0)


def test_a_motion_midway_still_reads_the_measured_joints(fast):
    """Far from its end a from-rest plan is refused by the gate anyway; start_position reads the measured joints."""
    station, cell = fast
    station.home(wait=True)
    station.move_joints(GOAL_Q, moving_time_s=1.0)
    with station._lock:
        trajectory = station.gate.commanded[0]
    cell.step(0.3)
    start = station.start_position()
    assert np.max(np.abs(start - trajectory.positions_rad[-1])) > 0.05
    assert np.allclose(start, station.joints_rad(), atol=0.02)
    station.wait_motion(5.0)
