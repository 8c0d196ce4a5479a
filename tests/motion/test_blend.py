"""Jerk-limited runs through waypoints (armlab.motion.blend): limits kept, waypoints passed exactly, no
stop at pass-through waypoints, rest at the ends, control-tick durations, speed scaling, smooth stops."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.blend import arm_limits, pass_velocities, plan_run, plan_stop, reference_state
from armlab.motion.safety import finite_difference_rates

ARM = load_arm("rx200")
POINTS = np.array([
    [0.0, -0.3, 0.3, 0.9, 0.0],
    [0.45, 0.05, 0.35, 1.0, 0.0],
    [0.9, 0.2, 0.1, 1.1, 0.3],
    [0.5, -0.2, -0.1, 1.2, 0.3],
])


def _rates(run):
    velocity, accel = finite_difference_rates(run.trajectory)
    return np.abs(velocity).max(axis=0), np.abs(accel).max(axis=0)


def test_a_blended_run_keeps_the_limits_passes_every_waypoint_and_ends_at_rest():
    limits = arm_limits(ARM)
    run = plan_run(POINTS, limits, tick_s=0.004)
    peak_v, peak_a = _rates(run)
    assert np.all(peak_v <= np.asarray(ARM.velocity_limit_rad_s) + 1e-9)
    assert np.all(peak_a <= np.asarray(ARM.accel_limit_rad_s2) + 1e-9)
    for point, t in zip(POINTS, run.arrival_s):  # at each waypoint at its arrival time (sample exactly there)
        assert np.allclose(run.trajectory.sample(t), point, atol=1e-9)
    _, v_end, _ = reference_state(run.trajectory, run.duration_s)
    assert np.allclose(v_end, 0.0)
    assert run.blended


def test_blending_does_not_stop_at_a_pass_through_waypoint_and_is_faster():
    limits = arm_limits(ARM)
    blended = plan_run(POINTS, limits)
    stopping = plan_run(POINTS, limits, stop_everywhere=True)
    t1 = blended.arrival_s[1]
    _, v_pass, _ = reference_state(blended.trajectory, t1)
    _, v_stop, _ = reference_state(stopping.trajectory, stopping.arrival_s[1])
    assert np.abs(v_pass).max() > 0.2  # still moving through waypoint 2
    assert np.abs(v_stop).max() < 0.05
    assert blended.duration_s < stopping.duration_s


def test_pass_velocity_is_zero_where_a_joint_reverses():
    points = np.array([[0.0, 0, 0, 0, 0], [0.5, 0.2, 0, 0, 0], [1.0, 0.0, 0, 0, 0]])
    velocities = pass_velocities(points, arm_limits(ARM))
    assert velocities[1, 0] > 0 and velocities[1, 1] == 0.0  # waist goes on, shoulder turns back
    assert np.all(velocities[0] == 0) and np.all(velocities[-1] == 0)


def test_segment_durations_are_whole_control_ticks():
    run = plan_run(POINTS, arm_limits(ARM), tick_s=0.004)
    for t in run.arrival_s:
        assert abs(t / 0.004 - round(t / 0.004)) < 1e-6


@pytest.mark.parametrize("speed", [0.1, 0.5])
def test_the_speed_override_scales_like_time(speed):
    full = plan_run(POINTS, arm_limits(ARM))
    slow = plan_run(POINTS, arm_limits(ARM).scaled(speed))
    assert slow.duration_s == pytest.approx(full.duration_s / speed, rel=0.02)
    peak_v, _ = _rates(slow)
    assert np.all(peak_v <= np.asarray(ARM.velocity_limit_rad_s) * speed + 1e-9)
    with pytest.raises(ValueError):
        arm_limits(ARM).scaled(0.0)


def test_a_run_from_a_moving_state_continues_it_smoothly():
    limits = arm_limits(ARM)
    run = plan_run(POINTS, limits)
    t = 0.5 * run.arrival_s[1]
    q, v, a = reference_state(run.trajectory, t)
    again = plan_run(np.vstack([q, POINTS[1:]]), limits.scaled(0.5), start_velocity=v, start_accel=a)
    first_step_velocity = (again.trajectory.positions_rad[1] - again.trajectory.positions_rad[0]) / again.trajectory.times_s[1]
    assert np.allclose(first_step_velocity, v, atol=0.1)  # no jump in velocity at the switch
    assert np.allclose(again.trajectory.positions_rad[-1], POINTS[-1])


def test_a_stop_brakes_within_the_limits_to_rest():
    limits = arm_limits(ARM)
    run = plan_run(POINTS, limits)
    q, v, a = reference_state(run.trajectory, run.arrival_s[1])
    stop = plan_stop(q, v, a, limits)
    velocity, accel = finite_difference_rates(stop)
    assert np.abs(accel).max() <= np.max(ARM.accel_limit_rad_s2) * 1.05
    assert np.abs(velocity[-1]).max() < 0.02
    assert stop.duration_s < 1.5


def test_a_trajectory_library_failure_is_a_clear_value_error():
    """Issue 18 item 2: ruckig's own errors (RuckigError here; 'ValueError: -101 is not a valid Result' in CI) are
    a ValueError that names the library, which the repeat job turns into a refused speed change."""
    from armlab.motion.blend import Limits, plan_run

    tiny = Limits(np.ones(2), np.full(2, 1e-3), np.full(2, 1e-3))
    with pytest.raises(ValueError, match=r"trajectory library \(ruckig\) found no trajectory"):
        plan_run(np.array([[0.0, 0.0], [1.0, 1.0]]), tiny, start_velocity=[1e3, 0.0])


@pytest.mark.parametrize("plan", ["run", "stop"])
def test_a_start_still_accelerating_near_the_velocity_limit_never_passes_it(plan):
    """A takeover at cruise speed while still accelerating (the waist at 99.5 % of its limit, accelerating at the
    limit toward it): the plan keeps the start velocity and stays within the velocity limit (an accelerating start
    carried over, a²/2j past it, was refused as 'waist moves at 3.164 rad/s ... above its velocity limit')."""
    limits = arm_limits(ARM)
    v_max, a_max = float(limits.velocity_rad_s[0]), float(limits.accel_rad_s2[0])
    start = np.array([-1.0, 0.0, 0.0, 0.9, 0.0])
    velocity = np.array([0.995 * v_max, 0.0, 0.0, 0.0, 0.0])
    accel = np.array([a_max, 0.0, 0.0, 0.0, 0.0])
    if plan == "run":
        trajectory = plan_run(np.array([start, start + [2.5, 0.0, 0.0, 0.0, 0.0]]), limits,
                              start_velocity=velocity, start_accel=accel, tick_s=0.004).trajectory
    else:
        trajectory = plan_stop(start, velocity, accel, limits)
    rates, _ = finite_difference_rates(trajectory)
    assert np.abs(rates[:, 0]).max() <= v_max + 1e-9, (np.abs(rates[:, 0]).max(), v_max)
    assert abs(rates[0, 0] - velocity[0]) <= a_max * float(trajectory.times_s[1]) + 1e-6  # the start velocity is kept
