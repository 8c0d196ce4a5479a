"""The ideal simulated servos' references between control ticks (armlab/devices/sim/servo_reference.py): the same
position and velocity as the trajectory's sample_trajectory, precomputed for every physics step, and from rest a
velocity that starts at 0 where the trajectory starts. Pure."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim.arm import sample_trajectory
from armlab.devices.sim.servo_reference import TrajectoryReference, servo_reference


def _random_trajectory(rng, samples: int) -> JointTrajectory:
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.002, 0.02, size=samples - 1))])
    return JointTrajectory(times, np.cumsum(rng.normal(size=(samples, 3)), axis=0) * 0.01)


@pytest.mark.parametrize("samples", [2, 3, 4, 12, 60])
def test_the_references_are_the_trajectory_samples(samples):
    rng = np.random.default_rng(samples)
    for _ in range(10):
        trajectory = _random_trajectory(rng, samples)
        reference = TrajectoryReference(trajectory)
        for t in [*np.linspace(-0.01, trajectory.duration_s + 0.01, 301), *trajectory.times_s]:
            position, velocity, _ = sample_trajectory(trajectory, t)
            assert np.allclose(reference.position_at(t), position, atol=1e-12)
            assert np.allclose(reference.velocity_at(t), velocity, atol=1e-12)


def test_from_rest_the_velocity_starts_at_zero_where_the_trajectory_starts():
    """A jog from rest begins with a 52 ms hold, then moves (the station's lead): extrapolated back over the hold, as a
    takeover's first half-segment is, the velocity reference started at -0.23 rad/s with the arm standing still."""
    dt, accel = 0.01, 4.9
    motion = accel * dt * dt * np.cumsum(np.arange(1, 31))  # velocity steps of accel*dt per sample
    positions = np.concatenate([[0.0, 0.0], motion])[:, None]
    times = np.concatenate([[0.0], 0.0517 + dt * np.arange(len(positions) - 1)])
    trajectory = JointTrajectory(times, positions)
    assert sample_trajectory(trajectory, 0.0)[1][0] < -0.2  # (what a takeover's reference does there)
    reference = TrajectoryReference(trajectory, from_rest=True)
    velocities = np.array([reference.velocity_at(t)[0] for t in np.arange(0.0, 0.2, 0.002)])
    assert velocities[0] == 0.0
    assert np.all(np.abs(np.diff(velocities)) / 0.002 <= accel * (1 + 1e-9))


def test_the_velocity_reference_is_that_of_the_step_middle_and_a_takeover_goes_on_at_the_running_velocity():
    rng = np.random.default_rng(3)
    running, new = _random_trajectory(rng, 20), _random_trajectory(rng, 20)
    ref_running, ref_new = TrajectoryReference(running), TrajectoryReference(new)
    step = 0.002
    position, velocity = servo_reference(ref_new, 1.0, None, 1.05, step)
    assert np.allclose(position, sample_trajectory(new, 0.05)[0]) and np.allclose(velocity, sample_trajectory(new, 0.051)[1])
    # inside the new trajectory's first half-segment the replaced one's velocity goes on
    _, velocity = servo_reference(ref_new, 1.0, (ref_running, 0.7), 1.0, step)
    assert np.allclose(velocity, sample_trajectory(running, 0.301)[1])
