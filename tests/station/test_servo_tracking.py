"""The simulated (ideal) servos follow a legal command within the acceleration limit: measured on the joints, not
only on the command (issue 18's motion continuity). Before the acceleration was fed forward, a lone fastest trapezoid
measured 1.14x the limit, a move whose acceleration reverses at once ~1.4x, and the bench's replacements 1.49-1.73x;
with it, but with references changed only at each 4 ms control tick (two physics steps) and sampled at the step's
start, 1.01-1.03x: MuJoCo integrates semi-implicitly and takes the velocity servo implicitly, so a joint exactly on its
trajectory read a velocity error of a*h/2..3h/2 and a position error of v*h, which the servos corrected and which moved
with every change of the commanded acceleration. Now the ideal servos follow their trajectory at every physics step
with the references the integrator is consistent with (armlab/devices/sim/servo_reference.py) and the joints follow
the command: at most the command's own figure. Measured on the simulation's clock at every control tick, the joints'
velocity difference over 20 ms (fast, synchronous simulation)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures
from station_helpers import at_rest

ARM = load_arm("rx200")
ACCEL = np.asarray(ARM.accel_limit_rad_s2, dtype=float)
MEASURED_MAX = 1.0


def _ratios(cell, during_s: float) -> tuple[float, float]:
    cell.step(during_s)
    return motion_figures(cell.stop_joint_recording()).ratio(ACCEL)


@pytest.mark.parametrize("goal_waist_rad", [1.5, -1.3])  # a trapezoid (cruising at the velocity limit), a triangle
def test_a_lone_fastest_move_is_followed_within_the_acceleration_limit(fast, goal_waist_rad):
    """Before: 1.14x (the trapezoid), 1.33x (the triangle, whose acceleration reverses at once at its apex); with the
    acceleration fed forward once per control tick 1.01x (the trapezoid, measured 0.996x now)."""
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    cell.start_joint_recording()
    station.move_joints([goal_waist_rad, 0.0, 0.0, 0.0, 0.0])
    # (the triangle's command reads 1.009-1.012x depending on the phase of the control ticks, its apex between two
    # 10 ms samples seen over 20 ms windows, and the joint follows it: 1.004x measured; the trapezoid's 0.993x)
    command, measured = _ratios(cell, 2.0)
    assert measured <= max(MEASURED_MAX, command), f"the waist accelerates at {measured:.4f}x the limit (command {command:.4f}x)"


def test_a_move_that_replaces_one_at_speed_is_followed_within_the_acceleration_limit(fast):
    """The reversal of issue 18 item 1 (the waist at ~3 rad/s), sent between two control ticks. Before: 1.11x; 0.982x
    now."""
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    station.move_joints([1.5, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.802)  # the waist turns at ~3 rad/s; half a control period past a tick
    cell.start_joint_recording()
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0])
    command, measured = _ratios(cell, 2.5)
    assert command <= 1.01
    assert measured <= MEASURED_MAX, f"the waist accelerates at {measured:.3f}x the limit"


def test_a_jog_and_its_release_are_followed_within_the_acceleration_limit(fast):
    """A hold-to-run jog at the top jog speed: its velocity steps once per sample (no jerk limit), then it brakes.
    Before: 1.11x; 0.982x now."""
    station, cell = fast
    at_rest(station, [-1.0, 0.0, 0.0, 0.0, 0.0])
    top = station.motion_config.jog_max_speed_rad_s
    cell.start_joint_recording()
    station.jog([top, 0.0, 0.0, 0.0, 0.0], source="pad")
    for _ in range(8):
        cell.step(0.05)
        assert station.heartbeat(source="pad")
    command, measured = _ratios(cell, 1.0)
    assert command <= 1.01
    assert measured <= MEASURED_MAX, f"the waist accelerates at {measured:.3f}x the limit"


def test_a_jog_from_rest_sent_between_two_control_ticks_is_followed_within_the_acceleration_limit(fast):
    """A jog from rest whose first sample already moved at accel*dt (before: the joints at 1.20x the limit over 20 ms
    on bench seed 4 once the servos followed their command exactly)."""
    station, cell = fast
    at_rest(station, [-1.0, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.002)
    cell.start_joint_recording()
    station.jog([0.0, 0.5, -0.5, 0.8, -0.8], source="pad")
    _, measured = _ratios(cell, 1.0)
    assert measured <= MEASURED_MAX, f"a joint accelerates at {measured:.4f}x the limit"
