"""The global speed override as time scaling of a planned path: the same joint path, run at a rate of the time it
was planned for. Pure: no devices.

A trajectory q(u) planned for u in [0, D] is run as q(u(t)) with du/dt = r(t): velocity q'(u)·r, acceleration
q''(u)·r² + q'(u)·dr/dt. A constant r = s ≤ 1 (a motion from rest at s of full speed) keeps the planned path and
scales velocity by s and acceleration by s², so it stays within the limits it was planned in. A change of speed
while the path runs (`retimed`) moves r from its old to its new value as fast as the acceleration limits allow at
each point of the path (continuous position and velocity; the change adds q'·dr/dt to the acceleration).
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput

RAMP_ACCEL_SHARE_TOTAL = 0.9  # the share of a joint's acceleration limit a re-timed path may use, ramp included


def checked_rate(rate: float, name: str = "rate") -> float:
    value = float(rate)
    if not (math.isfinite(value) and 0.01 <= value <= 100.0):
        raise InvalidInput(f"{name} must be a finite time rate from 0.01 to 100, got {rate!r}")
    return value


def warped(trajectory: JointTrajectory, start_s: float = 0.0, rate_start: float = 1.0, rate_end: float = 1.0,
           ramp_s: float = 0.0, rate_hz: float = 100.0) -> JointTrajectory:
    """The path of `trajectory` from its time start_s to its end, sampled at rate_hz, with the rate of its own time
    going linearly from rate_start to rate_end over ramp_s, then staying at rate_end. Starts at trajectory(start_s)
    exactly; ends on its last sample."""
    r0, r1 = checked_rate(rate_start, "rate_start"), checked_rate(rate_end, "rate_end")
    duration = trajectory.duration_s
    start = min(max(float(start_s), 0.0), duration)
    ramp = max(float(ramp_s), 0.0) if r0 != r1 else 0.0
    remaining = duration - start
    bound_s = ramp + remaining / min(r0, r1) + 2.0 / rate_hz
    t = np.arange(0.0, bound_s + 1.0 / rate_hz, 1.0 / rate_hz)
    if ramp > 0.0:
        in_ramp = np.minimum(t, ramp)
        u = start + r0 * in_ramp + 0.5 * (r1 - r0) * in_ramp**2 / ramp + r1 * np.maximum(t - ramp, 0.0)
    else:
        u = start + r1 * t
    past = np.flatnonzero(u >= duration - 1e-12)
    count = int(past[0]) + 1 if past.size else len(t)
    t, u = t[:count], np.minimum(u[:count], duration)
    if count < 2:  # nothing left to run: hold the end
        t, u = np.array([0.0, 1.0 / rate_hz]), np.array([duration, duration])
    positions = np.stack([np.interp(u, trajectory.times_s, column) for column in trajectory.positions_rad.T], axis=1)
    positions[0] = trajectory.sample(start)
    return JointTrajectory(t, positions)


def path_derivatives(trajectory: JointTrajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times, velocity, acceleration) of a sampled trajectory at its samples: velocity the mean of the two
    segments' slopes, acceleration their difference over the mean spacing (zero at the ends)."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    dof = positions.shape[1]
    if len(times) < 2:
        return times, np.zeros((len(times), dof)), np.zeros((len(times), dof))
    slopes = np.diff(positions, axis=0) / np.diff(times)[:, None]
    velocity = np.zeros_like(positions)
    accel = np.zeros_like(positions)
    velocity[0], velocity[-1] = slopes[0], slopes[-1]
    if len(times) > 2:
        velocity[1:-1] = 0.5 * (slopes[1:] + slopes[:-1])
        accel[1:-1] = np.diff(slopes, axis=0) / (0.5 * (times[2:] - times[:-2]))[:, None]
    return times, velocity, accel


def retimed(trajectory: JointTrajectory, start_s: float, rate_start: float, rate_end: float, accel_limit_rad_s2,
            rate_hz: float = 100.0, share: float = RAMP_ACCEL_SHARE_TOTAL) -> JointTrajectory:
    """Like `warped`, the path from start_s on with its time rate going from rate_start to rate_end, but the rate
    changes as fast as the acceleration limits allow at each point of the path: every joint's q''·r² + q'·dr/dt
    stays within share × its limit (when q''·r² alone does, as it does for a path planned within the limits and run
    at no more than full speed), integrated forward one sample at a time. Where the path already brakes at its limit
    the rate holds until it may change (a motion braking hard cannot be slowed more). rate_hz: only for a path of
    one sample (else the path's own sample spacing is kept)."""
    r, r_end = checked_rate(rate_start, "rate_start"), checked_rate(rate_end, "rate_end")
    limit = np.asarray(accel_limit_rad_s2, float) * share
    times, velocity, accel = path_derivatives(trajectory)
    duration = trajectory.duration_s
    u = min(max(float(start_s), 0.0), duration)
    ahead = times >= u - 1e-9
    if r_end > r and ahead.any():  # faster: never so fast that the path's own braking (q''·r²) leaves no margin
        worst = float(np.max(np.abs(accel[ahead]) / limit[None, :]))
        if worst > 0.0:
            r_end = max(r, min(r_end, math.sqrt(1.0 / worst)))
    # the path's own sample spacing: at rate 1 the samples are the path's (resampling between them would add corners)
    dt = float(np.median(np.diff(times))) if len(times) > 1 else 1.0 / rate_hz
    us = [u]
    for _ in range(int(1e6)):
        if u >= duration - 1e-12:
            break
        q1 = np.array([np.interp(u, times, column) for column in velocity.T])
        q2 = np.array([np.interp(u, times, column) for column in accel.T])
        want = r_end - r
        if abs(want) > 1e-12:
            lo, hi = -np.inf, np.inf
            for j in np.flatnonzero(np.abs(q1) > 1e-9):  # -L <= q2 r^2 + q1 r' <= L
                a, b = (-limit[j] - q2[j] * r * r) / q1[j], (limit[j] - q2[j] * r * r) / q1[j]
                lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
            cap = abs(want) / dt
            change = float(np.clip(math.copysign(cap, want), min(lo, 0.0), max(hi, 0.0)))
            if not math.isfinite(change):
                change = math.copysign(cap, want)
        else:
            change = 0.0
        u = min(u + r * dt + 0.5 * change * dt * dt, duration)
        r = r + change * dt
        r = min(r, r_end) if want > 0 else max(r, r_end) if want < 0 else r
        r = max(r, 1e-3)
        us.append(u)
    u_arr = np.asarray(us)
    if len(u_arr) < 2:
        u_arr = np.array([duration, duration])
    positions = np.stack([np.interp(u_arr, trajectory.times_s, column) for column in trajectory.positions_rad.T], axis=1)
    positions[0] = trajectory.sample(min(max(float(start_s), 0.0), duration))
    return JointTrajectory(np.arange(len(u_arr)) * dt, positions)


def paced(trajectory: JointTrajectory, fraction: float, accel_limit_rad_s2, from_rest: bool, rate_hz: float = 100.0) -> JointTrajectory:
    """A newly planned trajectory at `fraction` of its planned speed: time-scaled throughout when it starts from rest,
    else (it continues a running motion) at its own speed first, the rate brought to `fraction` within the limits."""
    if fraction == 1.0:
        return trajectory
    if from_rest:
        return warped(trajectory, 0.0, fraction, fraction, 0.0, rate_hz)
    return retimed(trajectory, 0.0, 1.0, fraction, accel_limit_rad_s2, rate_hz)
