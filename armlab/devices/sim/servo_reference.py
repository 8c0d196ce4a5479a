"""What the ideal simulated servos follow between control ticks: a commanded trajectory's position and velocity
references for each physics step, consistent with how MuJoCo integrates the arm.

MuJoCo integrates semi-implicitly (q += h * v_new) and takes the velocity servo and the joints' damping implicitly
(on v_new, the velocity the step moves with). A joint that follows the trajectory therefore moves over a step with
the velocity at the step's middle: that is the velocity reference that leaves the velocity servo nothing to
correct, with the position reference at the step's start. Referenced at the step's start and changed only at each
4 ms control tick (two physics steps), a joint on the trajectory read a velocity error of a*h/2..3h/2 and a
position error of v*h that the servos corrected; each change of the commanded acceleration moved those offsets, a
tracking transient the bench's 20 ms window saw as up to 1.03x the acceleration limit (issue 18).
"""

from __future__ import annotations

import bisect

import numpy as np

from armlab.devices.arm import JointTrajectory


def segment_middle_s(times_s: np.ndarray, i: int) -> float:
    """Where segment i's slope is its velocity: its midpoint; the first segment's as if it were as long as the next
    (a takeover's first segment is a piece of the running trajectory's: the velocity goes on as it ran there)."""
    if i == 0 and len(times_s) >= 3:
        return float(times_s[1] - 0.5 * (times_s[2] - times_s[1]))
    return float(0.5 * (times_s[i] + times_s[i + 1]))


class TrajectoryReference:
    """A trajectory's references at any time, precomputed once (the servos ask at every 2 ms physics step): the
    position interpolates the samples linearly; the velocity runs linearly between the segments' midpoints, where
    it is their slopes, down to rest at the last sample, and before the first midpoint continues the change after
    it (armlab.devices.sim.arm.sample_trajectory's velocity, exactly), except from rest (from_rest: no trajectory
    taken over): then it starts at 0 at the first sample and runs linearly to the first midpoint after it.
    Extrapolated back instead, a first segment longer than the next (a jog starts with a 52 ms hold) started the
    reference at -0.23 rad/s while the arm stood still, and the feed-forward (its change over a step) kicked the arm
    at 10x the acceleration limit; a plan spliced onto a hold (a first segment of 1.7 ms) at 1.2x. A regular first
    segment gives 0 there either way."""

    def __init__(self, trajectory: JointTrajectory, from_rest: bool = False) -> None:
        self.trajectory = trajectory
        times = np.asarray(trajectory.times_s, dtype=float)
        positions = np.asarray(trajectory.positions_rad, dtype=float)
        self._times, self._positions = times, positions
        slopes = np.diff(positions, axis=0) / np.diff(times)[:, None]
        if len(times) == 2:  # one segment: no change of slope to spread, its slope throughout
            self._knots_s = np.array([times[0], times[1]])
            self._velocities = np.vstack([slopes[0], slopes[0]])
        else:
            middles = [segment_middle_s(times, i) for i in range(len(times) - 1)]
            self._knots_s = np.array([*middles, times[-1]])
            self._velocities = np.vstack([slopes, np.zeros(positions.shape[1])])
            if from_rest:  # at rest at the first sample; a midpoint before it (a first segment shorter than half the
                later = self._knots_s > times[0]  # next: a plan spliced onto a hold) is left out
                self._knots_s = np.concatenate([[times[0]], self._knots_s[later]])
                self._velocities = np.vstack([np.zeros(positions.shape[1]), self._velocities[later]])
        # lookups at every physics step: plain lists for bisect, each piece's slope precomputed
        self._times_list, self._knots_list = times.tolist(), self._knots_s.tolist()
        self._slopes = slopes
        self._velocity_slopes = np.diff(self._velocities, axis=0) / np.diff(self._knots_s)[:, None]
        self._zero = np.zeros(positions.shape[1])
        # a takeover's velocity goes on as it ran until here (a trajectory of two samples has no change of slope to take)
        self.first_middle_s = segment_middle_s(times, 0) if len(times) >= 3 else -np.inf

    def position_at(self, t_s: float) -> np.ndarray:
        """The position reference t_s after the trajectory's start (clamped to its ends)."""
        times = self._times_list
        if t_s <= times[0]:
            return self._positions[0].copy()
        if t_s >= times[-1]:
            return self._positions[-1].copy()
        i = bisect.bisect_right(times, t_s) - 1
        return self._positions[i] + (t_s - times[i]) * self._slopes[i]

    def velocity_at(self, t_s: float) -> np.ndarray:
        """The velocity reference t_s after the trajectory's start (at rest outside it)."""
        if t_s < self._times_list[0] or t_s >= self._times_list[-1]:
            return self._zero
        knots = self._knots_list
        k = min(max(bisect.bisect_right(knots, t_s) - 1, 0), len(knots) - 2)
        return self._velocities[k] + (t_s - knots[k]) * self._velocity_slopes[k]


def servo_reference(reference: TrajectoryReference, start_s: float, taken_over: tuple[TrajectoryReference, float] | None,
                    sim_time_s: float, timestep_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The ideal servos' (position, velocity) references for the physics step that starts at sim_time_s: the position
    at the step's start, the velocity at its middle (the module's docstring says why). taken_over: the trajectory
    this one replaced and its start; until the new one's first midpoint its velocity goes on as it ran there (the
    new trajectory knows only the change of slope after its first sample)."""
    position = reference.position_at(sim_time_s - start_s)
    middle_s = sim_time_s + 0.5 * timestep_s
    if taken_over is not None and middle_s - start_s < reference.first_middle_s:
        running, running_start_s = taken_over
        return position, running.velocity_at(middle_s - running_start_s)
    return position, reference.velocity_at(middle_s - start_s)
