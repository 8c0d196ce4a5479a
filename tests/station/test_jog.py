"""Hold-to-run jogging: a zero jog ramps down, refusals, and the plan never leaves the joint limits or exceeds
the acceleration limit (heartbeats and the stop after the last one: test_jog_deadman.py, on the sim's clock)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import live
from armlab.errors import CommandRefused
from armlab.kinematics import load_arm
from armlab.motion import check_trajectory
from armlab.motion.jog import LIMIT_MARGIN_RAD, plan_jog
from armlab.motion.safety import finite_difference_rates
from station_helpers import back_to_idle, make_station, still_for, wait_sim

ARM = load_arm("rx200")
WAIST_RAD_S = 0.5


@pytest.fixture(scope="module")
def station(cell, db_path):
    station = make_station(cell, db_path)
    yield station
    station.close()


@pytest.fixture()
def idle(station):
    back_to_idle(station)
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0], moving_time_s=1.0, wait=True)
    yield station
    back_to_idle(station)


def test_a_zero_velocity_jog_ramps_down_at_once(cell, idle):
    station = idle
    station.jog([WAIST_RAD_S, 0, 0, 0, 0])
    wait_sim(cell, 0.2)
    station.jog([0, 0, 0, 0, 0])
    live.wait_for(lambda: not station.arm.is_moving(), 5, 0.005)
    assert still_for(cell, station, 0.2)


def test_jog_is_refused_outside_idle_and_teach_and_beyond_the_limits(idle):
    station = idle
    with pytest.raises(ValueError, match="waist"):
        station.jog([10.0, 0, 0, 0, 0])
    with pytest.raises(ValueError, match="5 values"):
        station.jog([0.1, 0])
    station.estop()
    with pytest.raises(CommandRefused):
        station.jog([0.1, 0, 0, 0, 0])
    assert not station.heartbeat()


@settings(max_examples=150, deadline=None, derandomize=True)
@given(
    q0=st.lists(st.floats(-1.0, 1.0), min_size=5, max_size=5),
    v0=st.lists(st.floats(-1.0, 1.0), min_size=5, max_size=5),
    target=st.lists(st.floats(-1.0, 1.0), min_size=5, max_size=5),
    hold_s=st.floats(0.05, 1.0),
)
def test_plan_jog_stays_in_the_limits_and_ends_at_rest(q0, v0, target, hold_s):
    lower, upper = np.asarray(ARM.lower_rad), np.asarray(ARM.upper_rad)
    # Start anywhere inside the limits (fractions of the range), moving or not.
    accel_limit = np.asarray(ARM.accel_limit_rad_s2)
    q_start = lower + (np.asarray(q0) + 1.0) / 2.0 * (upper - lower)
    # Moving or not, but able to stop before the limit ahead (as the jog it replaces always is).
    ahead = np.where(np.asarray(v0) > 0, upper - LIMIT_MARGIN_RAD - q_start, q_start - lower - LIMIT_MARGIN_RAD)
    v_start = np.asarray(v0) * np.minimum(np.asarray(ARM.velocity_limit_rad_s) * 0.5, np.sqrt(2 * accel_limit * np.maximum(ahead, 0.0)))
    trajectory = plan_jog(q_start, v_start, np.asarray(target) * np.asarray(ARM.velocity_limit_rad_s), hold_s,
                          lower, upper, ARM.accel_limit_rad_s2)
    positions = trajectory.positions_rad
    assert np.allclose(positions[0], q_start)
    velocity, accel = finite_difference_rates(trajectory)
    assert np.all(np.abs(accel) <= accel_limit * (1 + 1e-6) + 1e-9)
    assert np.allclose(velocity[-1], 0.0)
    moved_inside = (positions >= lower - 1e-9) & (positions <= upper + 1e-9)
    started_inside = (q_start >= lower + LIMIT_MARGIN_RAD) & (q_start <= upper - LIMIT_MARGIN_RAD)
    assert np.all(moved_inside[:, started_inside])
    # What the gate checks (limits, rates) passes whenever the start is inside the limits.
    if started_inside.all() and np.all(np.abs(v_start) <= np.asarray(ARM.velocity_limit_rad_s)):
        check_trajectory(_LimitsOnly(), trajectory, check_rates=False)


class _LimitsOnly:
    """The arm's joint limits without its geometry (this property is about joints, not the table)."""

    dof = ARM.dof
    joint_names = ARM.joint_names
    lower_rad, upper_rad = ARM.lower_rad, ARM.upper_rad

    def joint_frames(self, positions):
        frames = np.tile(np.eye(4), (len(positions), self.dof + 1, 1, 1))
        frames[:, :, 2, 3] = 1.0
        return frames
