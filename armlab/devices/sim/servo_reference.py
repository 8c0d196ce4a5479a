"""What the ideal simulated servos follow between control ticks: a commanded trajectory's position and velocity
references for each physics step, consistent with how MuJoCo integrates the arm.

MuJoCo integrates semi-implicitly (q += h * v_new) and takes the velocity servo and the joints' damping implicitly
(on v_new, the velocity the step moves with). A joint that follows the trajectory therefore moves over a step with
the velocity at the step's middle: that is the velocity reference that leaves the velocity servo nothing to
correct, with the position reference at the step's start. Referenced at the step's start and changed only at each
4 ms control tick (two physics steps), a joint on the trajectory read a velocity error of a*h/2..3h/2 and a
position error of v*h that the servos corrected; each change of the commanded acceleration moved those offsets, a
tracking transient the bench's 20 ms window saw as up to 1.03x the acceleration limit (issue 18).

The position reference is the velocity reference's integral (a joint that moves with that velocity is where it
says). It was the samples' straight lines instead: a joint moving with the velocity reference bows off a chord by up
to a*dt^2/8 (60 urad at 5 rad/s^2 between 10 ms samples) and the position servo pulled it back toward the chord at
every sample, a +-2 % wobble of the acceleration that shifted with each change of the commanded acceleration: the
measured joints at up to 1.0022x the limit where the command read 0.9986x (bench/motion_continuity.py, seed 1).
The integral stays within dt^2 * |change of acceleration| / 8 of the samples (<= 0.13 mrad at the limits); a
trajectory that takes over a running one carries on from the position the servos had reached, and each ends exactly at
its last sample (Followed blends the difference in).
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
    velocity runs linearly between the segments' midpoints, where it is their slopes, down to rest at the last
    sample, and before the first midpoint continues the change after it (armlab.devices.sim.arm.sample_trajectory's
    velocity, exactly), except from rest (from_rest: no trajectory taken over): then it starts at 0 at the first
    sample and runs linearly to the first midpoint after it. Extrapolated back instead, a first segment longer than
    the next (a jog starts with a 52 ms hold) started the reference at -0.23 rad/s while the arm stood still, and the
    feed-forward (its change over a step) kicked the arm at 10x the acceleration limit; a plan spliced onto a hold (a
    first segment of 1.7 ms) at 1.2x. A regular first segment gives 0 there either way. The position is the first
    sample plus the velocity's integral (the module's docstring says why)."""

    def __init__(self, trajectory: JointTrajectory, from_rest: bool = False) -> None:
        self.trajectory = trajectory
        times = np.asarray(trajectory.times_s, dtype=float)
        positions = np.asarray(trajectory.positions_rad, dtype=float)
        slopes = np.diff(positions, axis=0) / np.diff(times)[:, None]
        if len(times) == 2:  # one segment: no change of slope to spread, its slope throughout
            knots_s = np.array([times[0], times[1]])
            velocities = np.vstack([slopes[0], slopes[0]])
        else:
            knots_s = np.array([*(segment_middle_s(times, i) for i in range(len(times) - 1)), times[-1]])
            velocities = np.vstack([slopes, np.zeros(positions.shape[1])])
            if from_rest:  # at rest at the first sample; a midpoint before it (a first segment shorter than half the
                later = knots_s > times[0]  # next: a plan spliced onto a hold) is left out
                knots_s = np.concatenate([[times[0]], knots_s[later]])
                velocities = np.vstack([np.zeros(positions.shape[1]), velocities[later]])
        # lookups at every physics step: plain lists for bisect, each piece's slope precomputed
        self._start_s, self._end_s = float(times[0]), float(times[-1])
        self._knots_s, self._velocities = knots_s, velocities
        self._knots_list = knots_s.tolist()
        self._velocity_slopes = np.diff(velocities, axis=0) / np.diff(knots_s)[:, None]
        self._zero = np.zeros(positions.shape[1])
        # the position: the velocity's integral (trapezoids, exact for its linear pieces) at the first sample, every
        # knot inside the trajectory and its end
        self._breaks_s = [self._start_s, *(k for k in self._knots_list if self._start_s < k < self._end_s), self._end_s]
        at_breaks = [self._velocity(t) for t in self._breaks_s]
        integral = [positions[0].copy()]
        for i in range(len(self._breaks_s) - 1):
            integral.append(integral[-1] + 0.5 * (self._breaks_s[i + 1] - self._breaks_s[i]) * (at_breaks[i] + at_breaks[i + 1]))
        self._break_positions, self._break_velocities = integral, at_breaks
        # a takeover's velocity goes on as it ran until here (a trajectory of two samples has no change of slope to take)
        self.first_middle_s = segment_middle_s(times, 0) if len(times) >= 3 else -np.inf

    def _velocity(self, t_s: float) -> np.ndarray:
        """The velocity's linear piece at t_s (the first and last pieces extended beyond their knots)."""
        knots = self._knots_list
        k = min(max(bisect.bisect_right(knots, t_s) - 1, 0), len(knots) - 2)
        return self._velocities[k] + (t_s - knots[k]) * self._velocity_slopes[k]

    def position_at(self, t_s: float) -> np.ndarray:
        """The position reference t_s after the trajectory's start: the first sample plus the velocity reference's
        integral (constant before the start and after the end)."""
        t_s = min(max(t_s, self._start_s), self._end_s)
        i = min(bisect.bisect_right(self._breaks_s, t_s) - 1, len(self._breaks_s) - 2)
        since_s = t_s - self._breaks_s[i]
        return self._break_positions[i] + 0.5 * since_s * (self._break_velocities[i] + self._velocity(t_s))

    def velocity_at(self, t_s: float) -> np.ndarray:
        """The velocity reference t_s after the trajectory's start (at rest outside it)."""
        if t_s < self._start_s or t_s >= self._end_s:
            return self._zero
        return self._velocity(t_s)


def _blends(tau: float) -> tuple[float, float, float, float]:
    """(g, dg/dtau, h, dh/dtau) on [0, 1]: g = 6 tau^5 - 15 tau^4 + 10 tau^3 goes from 0 to 1 and h = tau - 6 tau^3 +
    8 tau^4 - 3 tau^5 from slope 1 to rest at 0, both with no curvature at either end (a blend built of them adds no
    step of acceleration where it starts or ends)."""
    tau = min(max(tau, 0.0), 1.0)
    g = tau**3 * (10.0 + tau * (6.0 * tau - 15.0))
    dg = 30.0 * tau**2 * (1.0 - tau) ** 2
    h = tau * (1.0 + tau**2 * (-6.0 + tau * (8.0 - 3.0 * tau)))
    dh = 1.0 + tau**2 * (-18.0 + tau * (32.0 - 15.0 * tau))
    return g, dg, h, dh


class Followed:
    """A trajectory as the ideal servos follow it from at_s (simulated s; the trajectory starts at start_s): its
    references plus a correction. The integral of the velocity reference misses the samples by up to
    dt^2 * |change of acceleration| / 8, and a trajectory that takes over a running one starts from where the servos
    have got to (position_rad at at_s, the correction changing at rate_rad_s there), so the correction blends from
    that to ending exactly at the last sample (Station.start_position plans the next motion from there), in the
    position and velocity references alike (_blends; at most ~6 * difference / span^2 of acceleration, 0.1 % of the
    limit on the bench's replacements). From rest (position_rad None): from the first sample."""

    def __init__(self, reference: TrajectoryReference, start_s: float, position_rad: np.ndarray | None = None,
                 at_s: float | None = None, rate_rad_s: np.ndarray | float = 0.0) -> None:
        self.reference, self.start_s = reference, float(start_s)
        times = reference.trajectory.times_s
        self._end_s = self.start_s + float(times[-1])
        self._from_s = self.start_s + float(times[0]) if at_s is None else float(at_s)
        offset = 0.0 if position_rad is None else position_rad - reference.position_at(self._from_s - self.start_s)
        self._offset_rad = offset
        self._change_rad = reference.trajectory.positions_rad[-1] - reference.position_at(times[-1]) - offset
        self._span_s = max(self._end_s - self._from_s, 1e-9)
        self._rate_rad_s = rate_rad_s if self._end_s > self._from_s else 0.0

    def _correction(self, sim_time_s: float) -> tuple[np.ndarray | float, np.ndarray | float]:
        """(the correction, its rate) at sim_time_s."""
        g, dg, h, dh = _blends((sim_time_s - self._from_s) / self._span_s)
        inside = self._from_s < sim_time_s < self._end_s
        rate = dg / self._span_s * self._change_rad + dh * self._rate_rad_s if inside else 0.0
        return self._offset_rad + g * self._change_rad + h * self._span_s * self._rate_rad_s, rate

    def position(self, sim_time_s: float) -> np.ndarray:
        return self.reference.position_at(sim_time_s - self.start_s) + self._correction(sim_time_s)[0]

    def velocity(self, sim_time_s: float) -> np.ndarray:
        velocity = self.reference.velocity_at(sim_time_s - self.start_s)
        return velocity + self._correction(sim_time_s)[1] if self._from_s < sim_time_s < self._end_s else velocity

    def correction_rate(self, sim_time_s: float) -> np.ndarray | float:
        """How fast the correction changes at sim_time_s (a trajectory taking over goes on from it)."""
        return self._correction(sim_time_s)[1]

    def handover_s(self) -> float:
        """When a takeover hands over from the replaced trajectory's references to this one's: its first midpoint."""
        return self.start_s + self.reference.first_middle_s

    def continuing(self, before: Followed, position_rad: np.ndarray, at_s: float) -> Followed:
        """This trajectory going on at at_s from where the servos have got to (position_rad), following `before`."""
        return Followed(self.reference, self.start_s, position_rad, at_s, before.correction_rate(at_s))


def followed_at(followed: Followed, taken_over: Followed | None, sim_time_s: float) -> Followed:
    """Whose references the servos follow at sim_time_s: the replaced trajectory's until the handover."""
    return taken_over if taken_over is not None and sim_time_s < followed.handover_s() else followed


def servo_reference(followed: Followed, taken_over: Followed | None, sim_time_s: float, timestep_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The ideal servos' (position, velocity) references for the physics step that starts at sim_time_s: the position
    at the step's start, the velocity at its middle (the module's docstring says why). taken_over: the trajectory
    this one replaced; until the new one's first midpoint its references go on as they ran there (the new trajectory
    knows only the change of slope after its first sample), and there the new one's position carries on from its."""
    middle_s = sim_time_s + 0.5 * timestep_s
    return followed_at(followed, taken_over, sim_time_s).position(sim_time_s), followed_at(followed, taken_over, middle_s).velocity(middle_s)
