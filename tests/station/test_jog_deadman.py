"""Issue 18 item 5: the deadman lets go in time. Hold-to-run jogs continue while heartbeats arrive; after the
last one the arm starts braking within jog_hold_s (MoveIt Servo: 0.1 s) and stops at the acceleration limit,
so the stopping distance is at most one timeout's travel plus the braking distance the limits allow; the
top jog speed keeps that short. Measured on the simulation's clock at every control tick (fast, synchronous)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures

ARM = load_arm("rx200")
ACCEL = float(ARM.accel_limit_rad_s2[0])
OPERATOR_STOP_RAD = 0.25  # ~14 deg of waist, 0.1 m at the arm's reach: what a released jog may still travel



@pytest.mark.parametrize("phase_s", [0.0, 0.003, 0.006, 0.009])
@pytest.mark.parametrize("speed_percent", [25, 50, 100])
def test_a_released_jog_brakes_within_the_timeout_and_stops_at_the_acceleration_limit(fast, speed_percent, phase_s):
    """phase_s: where between two 10 ms samples the jog and its heartbeats arrive (the bound held at one phase
    and not at another)."""
    station, cell = fast
    station.move_joints([-1.5, 0.0, 0.0, 0.0, 0.0], wait=True)
    station.wait_motion(5.0)
    cell.step(0.01 - (cell.sim_time_s % 0.01) + phase_s)
    config = station.motion_config
    top_rad_s = min(getattr(config, "jog_max_speed_rad_s", np.inf), float(ARM.velocity_limit_rad_s[0]))  # the fastest jog allowed
    hold_s = config.jog_hold_s
    speed = top_rad_s * speed_percent / 100.0
    station.jog([top_rad_s, 0, 0, 0, 0], source="pad", speed_percent=speed_percent)
    assert not station.heartbeat(source="someone else")  # only the jogging controller extends it
    for _ in range(20):  # 1 s of heartbeats, one per 0.05 s of sim time
        cell.step(0.05)
        assert station.heartbeat(source="pad"), "the jog ended while heartbeats arrived"
    released_s, q_released = cell.sim_time_s, station.arm.reference_rad[0]
    cell.start_joint_recording()
    cell.step(1.0)
    trace = cell.stop_joint_recording()
    reference, times = trace["reference_rad"][:, 0], trace["time_s"]
    velocity = np.diff(reference) / np.diff(times)
    assert abs(velocity[0] - speed) < 0.01 * speed  # at speed when released
    braking_s = times[int(np.flatnonzero(velocity < speed * (1 - 1e-3))[0])] - released_s
    stopped = int(np.flatnonzero(np.abs(velocity) < 1e-6)[0])
    stopped_s = times[stopped] - released_s
    command_rad = reference[stopped] - q_released
    measured_rad = float(np.max(trace["position_rad"][:, 0])) - q_released
    bound_rad = speed * hold_s + speed**2 / (2 * ACCEL)
    # The command brakes within the timeout and travels no more than the bound (bench/motion_continuity once
    # showed braking 8 ms late and 0.229 rad commanded against a 0.224 rad bound at 100 %); the measured joint
    # follows the servos, which lag the command by a few ms.
    assert braking_s <= hold_s + 1e-6, f"braking began {braking_s:.3f} s after the last heartbeat"
    assert stopped_s <= hold_s + speed / ACCEL + 0.02, f"stopped {stopped_s:.3f} s after the last heartbeat"
    assert command_rad <= bound_rad and measured_rad <= bound_rad + 0.01, (command_rad, measured_rad, bound_rad)
    assert measured_rad <= OPERATOR_STOP_RAD, f"a jog at {speed:.2f} rad/s released travels {measured_rad:.2f} rad"
    assert motion_figures(trace).ratio([ACCEL] * 5)[0] <= 1.01  # braking at the acceleration limit, not beyond


def test_a_jog_faster_than_the_jog_limit_is_refused(fast):
    station, _ = fast
    top = getattr(station.motion_config, "jog_max_speed_rad_s", float(ARM.velocity_limit_rad_s[0]))
    with pytest.raises(ValueError, match="waist.*jog limit"):
        station.jog([top * 1.5, 0, 0, 0, 0])
    assert not station.arm.is_moving()
