"""A new motion that replaces a running one without a jump: where it takes over and how the two join.

The arm tracks a trajectory "from now". A replacement is planned from the state the running trajectory
will be in at its first sample lead_s or more later (the handover), and commanded as the running trajectory
until then followed by the new plan: position, velocity and acceleration of the command stay continuous, and the time spent
planning and checking is covered by the lead (the splice is trimmed to the moment it is sent). The state
is taken from the commanded reference, not from the servos' noisy readings; the gate still checks that the
first sample is where the arm is measured. Pure: no devices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PlanRefused

REST_SPEED_RAD_S = 1e-6  # a reference slower than this (every joint) is at rest


@dataclass(frozen=True)
class Handover:
    """Where a replacement takes over. planned_at_s: the clock time the splice's t = 0 stands for (the running
    trajectory's sample at or before the moment it was planned); prefix: the running trajectory from then until
    the handover (its own samples); position_rad,
    velocity_rad_s, accel_rad_s2: the commanded state at the end of the prefix (shape (dof,) each).
    source_id: which command it was taken from (the gate's count), so a stale handover is noticed; period_s: the
    running trajectory's sample period before the handover."""

    planned_at_s: float
    prefix: JointTrajectory
    position_rad: np.ndarray
    velocity_rad_s: np.ndarray
    accel_rad_s2: np.ndarray
    source_id: int = 0
    period_s: float = 0.01

    @property
    def lead_s(self) -> float:
        """From planned_at_s to the handover."""
        return self.prefix.duration_s

    @property
    def takes_over_s(self) -> float:
        """The clock time at which the new plan takes over."""
        return self.planned_at_s + self.prefix.duration_s

    @property
    def segment_velocity_rad_s(self) -> np.ndarray:
        """The velocity of the prefix's last sample segment: where a plan whose velocity steps once per sample
        (a jog) continues from. At a trajectory's end the state is at rest but its last segment still moves
        (a·h/2 after a braking ramp): the segment's own slope, so the jog's first step is one a·h from it."""
        times, positions = self.prefix.times_s, self.prefix.positions_rad
        if len(times) >= 2 and times[-1] > times[-2]:
            return (positions[-1] - positions[-2]) / (times[-1] - times[-2])
        return self.velocity_rad_s - 0.5 * self.accel_rad_s2 * self.period_s

    @property
    def at_rest(self) -> bool:
        return bool(np.all(np.abs(self.velocity_rad_s) < REST_SPEED_RAD_S) and np.all(np.abs(self.accel_rad_s2) < 1e-3))


def sample_positions(trajectory: JointTrajectory, t_s: np.ndarray) -> np.ndarray:
    """Positions (len(t_s), dof) of a piecewise-linear trajectory at times t_s (clamped to its ends)."""
    return np.stack([np.interp(t_s, trajectory.times_s, column) for column in trajectory.positions_rad.T], axis=1)


def reference_velocity(trajectory: JointTrajectory, t_s: float) -> np.ndarray:
    """The commanded velocity at t_s: the slope of the sample segment containing it (zero outside)."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    if t_s < times[0] or t_s >= times[-1]:
        return np.zeros(positions.shape[1])
    i = int(np.searchsorted(times, t_s, side="right")) - 1
    return (positions[i + 1] - positions[i]) / (times[i + 1] - times[i])


def take_over(running: JointTrajectory, running_start_s: float, now_s: float, lead_s: float, rate_hz: float,
              source_id: int = 0) -> Handover | None:
    """The handover at the running trajectory's first sample at least lead_s after now_s (its start was
    running_start_s, clock seconds), or None when it has already ended (the arm holds its last sample).

    The prefix keeps the running trajectory's own samples, so the command is exactly the one already running
    until the handover. The state there is read from the samples before it: velocity from the last difference
    advanced half a sample by the acceleration (so the new plan's first difference continues the old ones),
    acceleration from the last second difference. rate_hz: the fallback sample rate of a two-sample trajectory."""
    times, positions = running.times_s, running.positions_rad
    t_now = now_s - running_start_s
    index = int(np.searchsorted(times, t_now + lead_s - 1e-9))
    if t_now >= running.duration_s or index >= len(times) - 1 or len(times) < 3:
        # It ends inside the lead: taken over at rest after its end (handed over at its last sample instead, less than
        # the lead ahead, the new plan's first segment began before the servos took it, at the last segment's slope
        # where their reference had run down to rest: a jog on from there, 1.3-1.4x the limit; bench seed 5).
        return _hold_after_end(running, running_start_s, t_now, lead_s, rate_hz, source_id)
    index = max(index, 2)
    # The prefix starts at the running trajectory's sample at or before now (its t = 0 is in the past: the gate
    # trims it to the moment it is sent), so its sample spacing stays the running trajectory's own.
    # (A motion from rest starts at the control tick that takes it, up to one control period after it was sent: taken
    # over before that, the prefix starts at its first sample, planned_at_s in the future.)
    before = max(min(int(np.searchsorted(times, t_now, side="right")) - 1, index - 1), 0)
    prefix = JointTrajectory(times[before : index + 1] - times[before], positions[before : index + 1].copy())
    planned_at_s = running_start_s + float(times[before])
    period = float(times[index] - times[index - 1])
    period_before = float(times[index - 1] - times[index - 2])
    v_last = (positions[index] - positions[index - 1]) / period
    v_before = (positions[index - 1] - positions[index - 2]) / period_before
    accel = (v_last - v_before) / (0.5 * (period + period_before))
    velocity = v_last + 0.5 * accel * period
    return Handover(planned_at_s, prefix, positions[index].copy(), velocity, accel, source_id, period)


def _hold_after_end(running: JointTrajectory, running_start_s: float, t_now: float, lead_s: float, rate_hz: float,
                    source_id: int) -> Handover | None:
    """The handover of a running trajectory that ends inside the lead (t_now before its end) or ended less than a sample
    period ago; None once it ended a period or more ago. Its last segment still moved (a·h/2 after a braking ramp): a
    plan from rest starting at once would step the command by its own first step plus that, so the replacement takes
    over after holding the last sample whole periods, at rest, at least lead_s from now (the handover's t = 0 is the
    end, in the future when it has yet to come: the gate starts the command there and the running one runs out)."""
    times, positions = running.times_s, running.positions_rad
    period = float(times[-1] - times[-2]) if len(times) > 2 else 1.0 / rate_hz  # (two samples: a hold of any length)
    since_end_s = t_now - running.duration_s
    if since_end_s >= period or period <= 0.0:
        return None
    hold_s = period * max(1, math.ceil((since_end_s + lead_s) / period - 1e-9))
    last = positions[-1]
    prefix = JointTrajectory(np.array([0.0, hold_s]), np.vstack([last, last]))
    zeros = np.zeros(positions.shape[1])
    return Handover(running_start_s + float(times[-1]), prefix, last.copy(), zeros, zeros.copy(), source_id, period)


def splice(handover: Handover, new: JointTrajectory) -> JointTrajectory:
    """The command that replaces the running trajectory: its prefix, then `new` (which must start at the
    handover position; PlanRefused otherwise)."""
    gap = float(np.max(np.abs(new.positions_rad[0] - handover.position_rad)))
    if gap > 1e-9:
        raise PlanRefused(f"the new plan starts {gap:.2e} rad from the handover position")
    prefix = handover.prefix
    times = np.concatenate([prefix.times_s, prefix.duration_s + new.times_s[1:]])
    positions = np.vstack([prefix.positions_rad, new.positions_rad[1:]])
    return JointTrajectory(times, positions)


def trimmed(trajectory: JointTrajectory, elapsed_s: float) -> JointTrajectory:
    """The part of `trajectory` after elapsed_s, restarting at t = 0 (its first sample interpolated)."""
    if elapsed_s <= 0.0:
        return trajectory
    times = trajectory.times_s
    keep = times > elapsed_s + 1e-9
    if not keep.any():
        last = trajectory.positions_rad[-1]
        return JointTrajectory(np.array([0.0, times[-1] - times[-2] if len(times) > 1 else 0.01]), np.vstack([last, last]))
    first = sample_positions(trajectory, np.array([elapsed_s]))
    return JointTrajectory(np.concatenate([[0.0], times[keep] - elapsed_s]), np.vstack([first, trajectory.positions_rad[keep]]))


def continuity_problem(trajectory: JointTrajectory, position_rad, velocity_rad_s, accel_limit_rad_s2, names=None) -> str | None:
    """None when `trajectory` continues a reference at (position_rad, velocity_rad_s): it starts there and its
    first velocity differs by no more than the acceleration limit allows over its first sample; else why not."""
    position = np.asarray(position_rad, float)
    velocity = np.asarray(velocity_rad_s, float)
    times, positions = trajectory.times_s, trajectory.positions_rad
    dt = float(times[1] - times[0]) if len(times) > 1 else 0.0
    first_velocity = (positions[1] - positions[0]) / dt if dt > 0 else np.zeros_like(velocity)
    jump = np.abs(positions[0] - position)
    change = np.abs(first_velocity - velocity)
    allowed = np.asarray(accel_limit_rad_s2, float) * max(dt, 0.01) * 1.5 + 1e-3
    joint = int(np.argmax(change / allowed))
    name = names[joint] if names is not None else f"joint {joint}"
    if np.max(jump) > 1e-3:
        index = int(np.argmax(jump))
        which = names[index] if names is not None else f"joint {index}"
        return f"it starts {jump[index]:.3f} rad from where {which} is commanded to be while it moves at {velocity[index]:.2f} rad/s"
    if change[joint] > allowed[joint]:
        return (f"it would change {name}'s velocity from {velocity[joint]:.2f} to {first_velocity[joint]:.2f} rad/s at once "
                "(more than the acceleration limit allows)")
    return None
