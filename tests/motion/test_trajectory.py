"""Joint moves: no planned trajectory exceeds the limits; timing semantics; clamping reported; bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from armlab.kinematics import load_arm
from armlab.motion.planning_limits import PLANNING_ACCEL_FRACTION
from armlab.motion.trajectory import plan_joint_move, plan_joint_move_timed, trapezoid_profile

ARM = load_arm("rx200")
RTOL = 1e-6


def _joint_vector(draw):
    fractions = draw(st.lists(st.floats(0.0, 1.0), min_size=ARM.dof, max_size=ARM.dof))
    return np.clip(ARM.lower_rad + np.asarray(fractions) * (ARM.upper_rad - ARM.lower_rad), ARM.lower_rad, ARM.upper_rad)


@st.composite
def moves(draw):
    q_start, q_goal = _joint_vector(draw), _joint_vector(draw)
    if draw(st.booleans()):  # sometimes a short move of a few joints: exercises the triangular profile
        mask = np.asarray(draw(st.lists(st.booleans(), min_size=ARM.dof, max_size=ARM.dof)))
        q_goal = np.where(mask, q_start + (q_goal - q_start) * 0.02, q_start)
    moving_time = draw(st.one_of(st.none(), st.floats(0.01, 6.0)))
    accel_time = draw(st.one_of(st.none(), st.floats(0.0, 4.0)))
    return q_start, q_goal, moving_time, accel_time


def _rates_from_rest(trajectory):
    """Finite-difference velocity and acceleration, with the arm at rest before and after (padding)."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    dt = float(np.diff(times).max())
    padded = np.vstack([positions[:1], positions, positions[-1:]])
    velocity = np.diff(padded, axis=0) / dt
    accel = np.diff(velocity, axis=0) / dt
    return velocity, accel


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(moves())
def test_no_planned_trajectory_exceeds_limits(move):
    q_start, q_goal, moving_time, accel_time = move
    trajectory, timing = plan_joint_move_timed(q_start, q_goal, ARM, moving_time, accel_time)
    times, positions = trajectory.times_s, trajectory.positions_rad
    dt = np.diff(times)
    assert dt.max() <= 0.01 + 1e-12 and np.allclose(dt, dt[0])  # uniform, ≥ 100 Hz
    np.testing.assert_array_equal(positions[0], q_start)
    np.testing.assert_array_equal(positions[-1], q_goal)
    assert np.all(positions >= ARM.lower_rad - 1e-12) and np.all(positions <= ARM.upper_rad + 1e-12)
    velocity, accel = _rates_from_rest(trajectory)
    assert np.all(np.abs(velocity) <= ARM.velocity_limit_rad_s * (1 + RTOL))
    assert np.all(np.abs(accel) <= ARM.accel_limit_rad_s2 * (1 + RTOL))
    # Interbotix semantics: a feasible moving time is kept exactly; an infeasible one only ever grows.
    if moving_time is not None:
        assert trajectory.duration_s >= moving_time - 1e-12
        if not any("moving_time_s" in note for note in timing.clamped):
            assert math.isclose(trajectory.duration_s, moving_time, rel_tol=1e-12)


@settings(max_examples=100, deadline=None)
@given(moves())
def test_joints_are_synchronised_on_one_profile(move):
    q_start, q_goal, moving_time, accel_time = move
    delta = q_goal - q_start
    if np.max(np.abs(delta)) < 1e-6:
        return
    trajectory = plan_joint_move(q_start, q_goal, ARM, moving_time, accel_time)
    lead = int(np.argmax(np.abs(delta)))
    s = (trajectory.positions_rad[:, lead] - q_start[lead]) / delta[lead]
    expected = q_start[None, :] + s[:, None] * delta[None, :]
    np.testing.assert_allclose(trajectory.positions_rad, expected, atol=1e-9)  # straight line in joint space
    assert np.all(np.diff(s) >= -1e-12)  # never reverses


def test_fastest_move_touches_a_limit_and_the_shoulder_is_the_slow_joint():
    q_start = np.zeros(5)
    q_goal = np.array([0.0, 1.5, 0.0, 0.0, 0.0])  # shoulder only: 1 rad/s, 5 rad/s²
    trajectory, timing = plan_joint_move_timed(q_start, q_goal, ARM)
    # Trapezoid at the limits (the acceleration at the planning fraction f of 5 rad/s²): ramp 1/5f s, cruise at
    # 1 rad/s: T = 1.5/1 + 1/5f (1.702 s at f = 0.99), lengthened to whole 10 ms samples.
    ramp_s = 1.0 / (5.0 * PLANNING_ACCEL_FRACTION)
    assert math.isclose(timing.moving_time_s, math.ceil((1.5 + ramp_s) * 100 - 1e-9) / 100, rel_tol=1e-4)
    assert math.isclose(timing.accel_time_s, ramp_s, rel_tol=1e-4)
    velocity, accel = _rates_from_rest(trajectory)
    assert np.abs(velocity[:, 1]).max() > 0.99  # reaches its velocity limit: as fast as allowed
    assert timing.clamped == ()


def test_too_short_moving_time_is_stretched_and_reported():
    trajectory, timing = plan_joint_move_timed(np.zeros(5), np.array([2.0, 0.0, 0.0, 0.0, 0.0]), ARM, moving_time_s=0.2)
    # waist 2 rad at π rad/s and 5f rad/s² (f the planning fraction): triangle would peak above π, so trapezoid:
    # 2/π + π/5f ≈ 1.2713 s at f = 0.99, lengthened to whole 10 ms sample periods (a fastest move ends on the grid): 1.28 s
    expected_s = math.ceil((2 / 3.14159 + 3.14159 / (5 * PLANNING_ACCEL_FRACTION)) * 100) / 100
    assert math.isclose(trajectory.duration_s, expected_s, rel_tol=1e-4)
    assert len(timing.clamped) == 1 and "moving_time_s 0.200 →" in timing.clamped[0]


def test_feasible_timing_is_honoured_and_an_impossible_ramp_is_clamped():
    q_goal = np.array([0.5, 0.2, -0.3, 0.1, 0.0])
    trajectory, timing = plan_joint_move_timed(np.zeros(5), q_goal, ARM, moving_time_s=2.0, accel_time_s=0.3)
    assert (timing.moving_time_s, timing.accel_time_s, timing.clamped) == (2.0, 0.3, ())
    s = trapezoid_profile(np.array([0.3, 1.0, 1.7]), 2.0, 0.3)
    np.testing.assert_allclose(trajectory.sample(1.0), s[1] * q_goal, atol=1e-9)
    np.testing.assert_allclose(s, [0.3 / 1.7 / 2, 0.5, 1 - 0.3 / 1.7 / 2])

    _, timing = plan_joint_move_timed(np.zeros(5), q_goal, ARM, moving_time_s=2.0, accel_time_s=1.5)
    assert timing.accel_time_s == 1.0 and "accel_time_s 1.500 → 1.000" in timing.clamped[0]


def test_no_motion_is_a_constant_trajectory():
    q = np.array([0.1, -0.2, 0.3, 0.4, -0.5])
    trajectory = plan_joint_move(q, q, ARM, moving_time_s=1.0)
    assert trajectory.duration_s == 1.0
    np.testing.assert_array_equal(trajectory.positions_rad, np.repeat(q[None], trajectory.times_s.size, axis=0))


@pytest.mark.parametrize(
    "q_start, q_goal, kwargs, message",
    [
        (np.zeros(5), np.array([0, 0, 0, 0, np.nan]), {}, "q_goal must be finite"),
        (np.zeros(4), np.zeros(5), {}, r"q_start must have shape \(5,\)"),
        (np.zeros(5), np.array([0, 2.5, 0, 0, 0]), {}, "q_goal: shoulder = 2.5000 rad is outside its limits"),
        (np.array([0, 0, -2.0, 0, 0]), np.zeros(5), {}, "q_start: elbow"),
        (np.zeros(5), np.ones(5) * 0.1, {"moving_time_s": -1.0}, "moving_time_s must be"),
        (np.zeros(5), np.ones(5) * 0.1, {"accel_time_s": math.inf}, "accel_time_s must be"),
    ],
)
def test_bad_input_is_a_clear_value_error(q_start, q_goal, kwargs, message):
    with pytest.raises(ValueError, match=message):
        plan_joint_move(q_start, q_goal, ARM, **kwargs)


def test_a_measured_start_a_hair_outside_a_limit_is_moved_onto_it_and_reported():
    q_start = np.array([0.0, ARM.lower_rad[1] - 0.005, 0.0, 0.0, 0.0])  # the sim may sag just past a limit
    trajectory, timing = plan_joint_move_timed(q_start, np.zeros(5), ARM)
    assert trajectory.positions_rad[0, 1] == ARM.lower_rad[1]
    assert any("start moved onto the joint limits: shoulder" in note for note in timing.clamped)
    with pytest.raises(ValueError, match="q_start: shoulder"):
        plan_joint_move(np.array([0.0, ARM.lower_rad[1] - 0.02, 0.0, 0.0, 0.0]), np.zeros(5), ARM)


def test_a_fastest_move_as_the_servos_follow_it_stays_within_the_acceleration_limit():
    """The servos interpolate the samples linearly at their 4 ms tick; a move at the limits sampled on a grid
    of 9.85 ms measured 1.005x the limit over 20 ms windows (bench/motion_continuity.py): fastest moves take
    whole sample periods, so no window of the followed command passes the limit."""
    from armlab.motion.measure import motion_figures

    rng = np.random.default_rng(7)
    lower, upper = np.asarray(ARM.lower_rad), np.asarray(ARM.upper_rad)
    tick_s, worst = 0.004, 0.0
    for _ in range(40):
        q0, q1 = rng.uniform(lower * 0.8, upper * 0.8), rng.uniform(lower * 0.8, upper * 0.8)
        trajectory = plan_joint_move(q0, q1, ARM)
        for offset_s in (0.0, 0.001, 0.0025):
            ticks = np.arange(-0.05 + offset_s, trajectory.duration_s + 0.05, tick_s)
            reference = np.column_stack([np.interp(ticks, trajectory.times_s, trajectory.positions_rad[:, j])
                                         for j in range(ARM.dof)])
            trace = {"time_s": ticks, "reference_rad": reference, "velocity_rad_s": np.zeros_like(reference)}
            command, _ = motion_figures(trace).ratio(ARM.accel_limit_rad_s2)
            worst = max(worst, command)
    assert worst <= 1.0 + 1e-9, f"the followed command reaches {worst:.4f}x the acceleration limit"
