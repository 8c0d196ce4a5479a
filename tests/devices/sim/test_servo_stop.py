"""The ideal servos bring a braking trajectory to rest at its last sample (issue 18's motion continuity, bench seed 9).

MuJoCo moves a joint over a physics step with the velocity at the step's middle, so a joint braking onto a trajectory's
last sample still moves at a*h/2 when the last step before it ends. The servos were then released to hold the last
sample with no deceleration fed forward, and the joint crept on for ~6 control ticks (here 1.2e-3 rad/s a tick
later, 2.5e-3 on bench seed 9's move); a move sent meanwhile the other way had its servos take that out on top of its
own acceleration (the waist measured 1.0108x the limit). Fast simulation: the clock is the simulation's."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm

ACCEL_RAD_S2 = float(load_arm("rx200").accel_limit_rad_s2[0])


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as sim:
        yield sim


def _bang_bang(q0: np.ndarray, samples: int, accel_rad_s2: float) -> JointTrajectory:
    """The waist from rest to rest in `samples` 10 ms samples, at +accel then -accel (braking at the limit to the end)."""
    times = np.arange(samples + 1) * 0.01
    half = times[-1] / 2.0
    waist = np.where(times <= half, 0.5 * accel_rad_s2 * times**2, accel_rad_s2 * half**2 - 0.5 * accel_rad_s2 * (times[-1] - times) ** 2)
    positions = np.repeat(q0[None, :], len(times), axis=0)
    positions[:, 0] += waist
    return JointTrajectory(times, positions)


@pytest.mark.parametrize("samples", [40, 41])  # starting at a 4 ms control tick: ends on a tick (400 ms), between two (410 ms)
def test_a_braking_trajectory_ends_at_rest(cell, samples):
    """Before: 1.2e-3 rad/s a control tick after a trajectory that ends on a tick (either phase now: 9e-6)."""
    cell.arm.command_trajectory(_bang_bang(cell.arm.read_joint_state().position_rad, samples, 0.99 * ACCEL_RAD_S2))
    while cell.arm.is_moving():
        cell.step(cell.control_period_s)
    cell.step(cell.control_period_s)
    speed = abs(float(cell.arm_velocities()[0]))
    assert speed < 1e-4, f"the waist still moves at {speed:.2e} rad/s a control tick after its trajectory ended"


def test_a_trajectory_sent_after_the_last_one_ended_but_before_the_next_tick_starts_from_rest(cell):
    """Sent after the last trajectory's end but before the servos' next tick let go of it (the station hands over then
    with a hold of the last sample, then the plan), the new one was taken as a takeover of a moving arm: its velocity
    reference before the hold's end extrapolated the plan's first change back, and the joint was driven the other way
    (bench seed 10: wrist_angle at -0.12 rad/s, its position reference stepping 0.5 mrad). Nothing runs on: it starts
    at rest."""
    braking = _bang_bang(cell.arm.read_joint_state().position_rad, 41, -0.99 * ACCEL_RAD_S2)  # ends 2 ms before a tick
    end_s = cell.arm.command_trajectory(braking) + braking.duration_s
    while cell.sim_time_s < end_s + 1e-9 or cell.next_control_s > cell.sim_time_s + 1e-9:
        cell.step(cell.timestep_s)  # to the first tick after the end, not yet run
    plan = _bang_bang(braking.positions_rad[-1], 40, 0.99 * ACCEL_RAD_S2)
    hold_s = 0.058
    after = JointTrajectory(np.concatenate([[0.0], hold_s + plan.times_s]), np.vstack([plan.positions_rad[:1], plan.positions_rad]))
    cell.start_joint_recording()
    cell.arm.command_trajectory(after, start_time_s=cell.sim_time_s)
    cell.step(0.2)
    trace = cell.stop_joint_recording()
    backwards = float(-np.min(trace["reference_velocity_rad_s"][:, 0]))
    assert backwards < 1e-6, f"the waist is driven back at {backwards:.3f} rad/s"
