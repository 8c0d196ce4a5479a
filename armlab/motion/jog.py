"""Hold-to-run jogging: a joint-velocity motion that runs out by itself.

plan_jog turns "move at these joint velocities" into a trajectory that ramps to them within the
acceleration limit, holds them for `hold_s`, then ramps down to rest, braking early wherever a joint
would otherwise pass its limit. Each heartbeat of the controlling client re-plans from where the
previous jog is now, so the arm keeps moving only while heartbeats arrive: when they stop, the last
plan ends `hold_s` (+ the ramp down) later with no thread or timer involved. Pure: no devices.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput

LIMIT_MARGIN_RAD = 0.01  # braking stops this far inside a joint limit


def checked_jog_velocity(velocity_rad_s, velocity_limit_rad_s, names) -> np.ndarray:
    """A finite (dof,) joint velocity within the limits, else ValueError naming the joint."""
    velocity = np.asarray(velocity_rad_s, dtype=float)
    limit = np.asarray(velocity_limit_rad_s, dtype=float)
    if velocity.shape != limit.shape:
        raise InvalidInput(f"velocity_rad_s must have {limit.size} values ({', '.join(names)}), got shape {velocity.shape}")
    if not np.all(np.isfinite(velocity)):
        raise InvalidInput("velocity_rad_s must be finite numbers")
    for index, name in enumerate(names):
        if abs(velocity[index]) > limit[index] + 1e-9:
            raise InvalidInput(f"joint '{name}' jog velocity {velocity[index]:.3f} rad/s is above its jog limit {limit[index]:.3f} rad/s")
    return velocity


def plan_jog(
    q0_rad,
    v0_rad_s,
    v_target_rad_s,
    hold_s: float,
    lower_rad,
    upper_rad,
    accel_limit_rad_s2,
    rate_hz: float = 100.0,
    margin: float = LIMIT_MARGIN_RAD,
) -> JointTrajectory:
    """A trajectory from q0 moving at v0 that reaches v_target, keeps it until hold_s (rounded down to the
    sample grid), then stops.

    Per joint: the velocity moves toward its target (v_target before hold_s, 0 after, 0 sooner when the
    braking distance would carry the joint past limit - margin) by at most accel·dt per sample.
    The result starts at q0, ends at rest and stays within the acceleration limit (finite differences);
    it stays inside the limits whenever the start can still stop in time (|v0|²/2a within the distance
    to the limit ahead, as for the reference state of the jog being replaced). v0: that reference
    velocity (zeros from rest). margin: how far inside a limit braking stops (LIMIT_MARGIN_RAD for joints;
    the Cartesian jog plans its distance along the line with it, in metres).
    """
    q = np.asarray(q0_rad, dtype=float).copy()
    v = np.asarray(v0_rad_s, dtype=float).copy()
    target = np.asarray(v_target_rad_s, dtype=float)
    accel = np.asarray(accel_limit_rad_s2, dtype=float)
    low = np.asarray(lower_rad, dtype=float) + margin
    high = np.asarray(upper_rad, dtype=float) - margin
    if not (math.isfinite(hold_s) and hold_s > 0.0 and rate_hz > 0.0):
        raise InvalidInput(f"hold_s and rate_hz must be positive, got {hold_s}, {rate_hz}")
    dt = 1.0 / rate_hz
    dv_max = accel * dt
    positions, t = [q.copy()], 0.0
    if not np.any(v):
        # From rest the first sample holds: the velocity steps once per sample, so a first sample already moving at
        # accel*dt needs twice the acceleration limit over its first half (at rest before it), which the samples' own
        # differences do not show (the ideal servos, following it exactly, measured 1.20x over 20 ms). Held, the step
        # to accel*dt is one sample's change, as every other. The hold counts toward hold_s (braking stays on time).
        positions.append(q.copy())
        t = dt
    max_steps = int((hold_s + float(np.max(np.abs(v) / accel)) + float(np.max(np.abs(target) / accel))) * rate_hz) + 10
    for _ in range(max_steps):
        # A step runs at the target only if it ends by hold_s: braking starts at the last sample inside the hold,
        # never up to a sample after it (which overran the deadman's bound by a sample's travel).
        goal = target if t + dt <= hold_s + 1e-9 else np.zeros_like(target)
        # Take the step toward the goal unless, after it, braking at the limit could no longer stop the joint
        # before its limit; then brake now. This keeps q + v|v|/2a inside the limits at every sample (true
        # at the start for a jog that replaces another one), so the joint never passes them.
        v_try = v + np.clip(goal - v, -dv_max, dv_max)
        reach = q + v_try * dt + v_try * np.abs(v_try) / (2.0 * accel)
        over = ((v_try > 0) & (reach > high)) | ((v_try < 0) & (reach < low))
        # Braking for a limit, the joint takes the fastest velocity toward it that can still stop inside it (on the
        # braking curve), braking no harder than the limit allows: full braking at every sample where the step toward
        # the goal was over, and the step back toward the goal at the next one, made the acceleration reverse at
        # every sample (the servos followed that chatter at 1.05x the acceleration limit).
        room = np.where(v_try > 0, high - q, q - low)
        on_curve = np.sign(v_try) * accel * (np.sqrt(dt * dt + 2.0 * np.maximum(room, 0.0) / accel) - dt)
        braked = np.where(v_try > 0, np.maximum(v - dv_max, np.minimum(v_try, on_curve)),
                          np.minimum(v + dv_max, np.maximum(v_try, on_curve)))
        v = np.where(over, braked, v_try)
        q = q + v * dt
        t += dt
        positions.append(q.copy())
        if t >= hold_s and not np.any(v):
            break
    positions_rad = np.asarray(positions)
    if len(positions_rad) < 2:
        positions_rad = np.vstack([positions_rad, positions_rad])
    times_s = np.arange(len(positions_rad)) * dt
    return JointTrajectory(times_s, positions_rad)


def reference_velocity(trajectory: JointTrajectory, t_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(position, velocity) of a sampled trajectory at t_s (clamped; zero velocity outside it)."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    if t_s <= times[0] or t_s >= times[-1]:
        index = 0 if t_s <= times[0] else -1
        return positions[index].copy(), np.zeros(positions.shape[1])
    i = int(np.searchsorted(times, t_s, side="right")) - 1
    slope = (positions[i + 1] - positions[i]) / (times[i + 1] - times[i])
    return positions[i] + slope * (t_s - times[i]), slope
