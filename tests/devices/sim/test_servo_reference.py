"""The ideal simulated servos' references between control ticks (armlab/devices/sim/servo_reference.py): the same
velocity as the trajectory's sample_trajectory, precomputed for every physics step, from rest a velocity that starts
at 0 where the trajectory starts, a position reference that is the velocity's integral, and trajectories followed
from where the servos are to exactly their last sample. Pure."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim.arm import sample_trajectory
from armlab.devices.sim.servo_reference import Followed, TrajectoryReference, servo_reference


def _random_trajectory(rng, samples: int) -> JointTrajectory:
    times = np.concatenate([[0.0], np.cumsum(rng.uniform(0.002, 0.02, size=samples - 1))])
    return JointTrajectory(times, np.cumsum(rng.normal(size=(samples, 3)), axis=0) * 0.01)


@pytest.mark.parametrize("samples", [2, 3, 4, 12, 60])
def test_the_velocity_reference_is_the_trajectory_samples_and_the_position_its_integral(samples):
    """The position reference was the samples' straight lines: a joint on the velocity reference (linear between the
    segments' midpoints) bowed off them by up to a*dt^2/8, and the position servo pulled it back at every sample."""
    rng = np.random.default_rng(samples)
    for _ in range(10):
        trajectory = _random_trajectory(rng, samples)
        reference = TrajectoryReference(trajectory)
        for t in [*np.linspace(-0.01, trajectory.duration_s + 0.01, 301), *trajectory.times_s]:
            assert np.allclose(reference.velocity_at(t), sample_trajectory(trajectory, t)[1], atol=1e-12)
        assert np.allclose(reference.position_at(-0.01), trajectory.positions_rad[0], atol=1e-15)
        for t in rng.uniform(0.0, trajectory.duration_s, 50):  # its slope is the velocity reference
            slope = (reference.position_at(t + 1e-7) - reference.position_at(t - 1e-7)) / 2e-7
            assert np.allclose(slope, reference.velocity_at(t), rtol=1e-5, atol=1e-5)


def test_a_followed_trajectory_ends_at_its_last_sample_and_a_takeover_goes_on_without_a_step():
    """The integral misses the samples by up to dt^2 * |change of acceleration| / 8: the servos would hold the arm
    that far from where the trajectory ends (where the station plans the next motion from), and a trajectory taking
    over from the integral of another would step the position reference by the difference."""
    times = np.arange(0.0, 0.805, 0.01)
    accel = np.where(times < 0.3, 5.0, np.where(times < 0.5, -5.0, 0.0))  # no jerk limit: the integral drifts most
    speed = np.concatenate([[0.0], np.cumsum(accel[:-1] * 0.01)])
    positions = np.concatenate([[0.0], np.cumsum(speed[:-1] * 0.01)])[:, None]
    first = Followed(TrajectoryReference(JointTrajectory(times, positions), from_rest=True), 2.0)
    assert abs(first.reference.position_at(0.8)[0] - positions[-1, 0]) > 1e-5  # the integral alone misses the end
    assert first.position(2.8)[0] == pytest.approx(positions[-1, 0], abs=1e-15)
    assert first.position(5.0)[0] == pytest.approx(positions[-1, 0], abs=1e-15)
    # a takeover at 2.25 s (the arm accelerating) by a plan that starts from the samples' line there
    at_s = 2.25
    start, state = sample_trajectory(JointTrajectory(times, positions), 0.25)[:2]
    later = np.arange(0.0, 0.405, 0.01)
    second = Followed(TrajectoryReference(JointTrajectory(later, start + state * later[:, None] - 2.5 * later[:, None] ** 2)), at_s)
    going_on = second.continuing(first, first.position(at_s), at_s)
    assert going_on.position(at_s)[0] == pytest.approx(first.position(at_s)[0], abs=1e-15)
    assert going_on.velocity(at_s + 1e-9)[0] - second.velocity(at_s + 1e-9)[0] == pytest.approx(
        first.velocity(at_s - 1e-9)[0] - first.reference.velocity_at(at_s - 1e-9 - 2.0)[0], abs=1e-6)
    assert going_on.position(at_s + 0.4)[0] == pytest.approx(second.reference.trajectory.positions_rad[-1, 0], abs=1e-15)
    # the correction's acceleration stays tiny: over a step, the velocity reference changes as the plan's does
    grid = np.arange(at_s + 0.001, at_s + 0.4, 0.002)
    change = np.diff([going_on.velocity(t)[0] - second.velocity(t)[0] for t in grid]) / 0.002
    assert np.max(np.abs(change)) < 0.01 * 5.0


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
    followed = Followed(ref_new, 1.0)
    position, velocity = servo_reference(followed, None, 1.05, step)
    assert np.allclose(position, followed.position(1.05)) and np.allclose(velocity, followed.velocity(1.051))
    assert not np.allclose(velocity, followed.velocity(1.05))
    # inside the new trajectory's first half-segment the replaced one's references go on
    taken_over = Followed(ref_running, 0.7)
    position, velocity = servo_reference(followed, taken_over, 1.0, step)
    assert np.allclose(velocity, sample_trajectory(running, 0.301)[1]) and np.allclose(position, taken_over.position(1.0))
