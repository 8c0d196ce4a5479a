"""Synchronised trapezoidal joint moves, timed like Interbotix's set_joint_positions.

All joints follow one scalar trapezoid s(t) in [0, 1] (q(t) = q_start + s(t) * (q_goal - q_start)), so
they start and stop together and the path is a straight line in joint space. `moving_time_s` is the
total duration and `accel_time_s` the duration of each ramp (Interbotix semantics). Either may be
stretched, never shrunk, so that no joint exceeds its velocity or acceleration limit; `MoveTiming`
reports what was changed and why. Pure functions: no device calls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.motion.planning_limits import planning_accel_rad_s2

DEFAULT_RATE_HZ = 100.0
# Relative slack when deciding whether a requested timing already satisfies the limits.
_FEASIBILITY_RTOL = 1e-9
# A measured start this close outside a position limit is moved onto the limit (noted), not refused.
START_TOLERANCE_RAD = 0.01
# Plans use velocity limits shrunk by this factor so rounding never lets a sampled trajectory touch the true limit (the
# acceleration: armlab.motion.planning_limits).
LIMIT_MARGIN = 1.0 - 1e-6


@dataclass(frozen=True)
class MoveTiming:
    """The timing actually used for a move and what was clamped.

    moving_time_s, accel_time_s: the durations used. requested_*: what the caller asked for (None =
    "as fast as the limits allow"). clamped: human-readable notes, empty when nothing was changed.
    peak_velocity_rad_s, peak_accel_rad_s2: per-joint peaks of the continuous profile, shape (dof,).
    """

    moving_time_s: float
    accel_time_s: float
    requested_moving_time_s: float | None
    requested_accel_time_s: float | None
    clamped: tuple[str, ...]
    peak_velocity_rad_s: np.ndarray
    peak_accel_rad_s2: np.ndarray


def _as_joint_vector(name: str, value, dof: int) -> np.ndarray:
    """A finite float vector of shape (dof,), else InvalidInput naming the argument."""
    array = np.asarray(value, dtype=float)
    if array.shape != (dof,):
        raise InvalidInput(f"{name} must have shape ({dof},), got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidInput(f"{name} must be finite, got {array.tolist()}")
    return array


def _check_duration(name: str, value: float | None) -> float | None:
    if value is None:
        return None
    value = float(value)
    if not math.isfinite(value) or value < 0.0:
        raise InvalidInput(f"{name} must be a finite number ≥ 0, got {value}")
    return value


def scalar_limits(
    delta_rad: np.ndarray, velocity_limit_rad_s: np.ndarray, accel_limit_rad_s2: np.ndarray
) -> tuple[float, float]:
    """Velocity and acceleration limits (1/s, 1/s²) of the shared profile s(t) for joint offsets delta_rad.

    Joint i moves |delta_i| * s, so s may go no faster than min_i v_i / |delta_i| (and likewise for
    acceleration). Joints that do not move impose no limit (inf).
    """
    magnitude = np.abs(delta_rad)
    moving = magnitude > 0.0
    if not np.any(moving):
        return math.inf, math.inf
    s_velocity = float(np.min(velocity_limit_rad_s[moving] / magnitude[moving]))
    s_accel = float(np.min(accel_limit_rad_s2[moving] / magnitude[moving]))
    return s_velocity, s_accel


def minimum_time(s_velocity: float, s_accel: float) -> tuple[float, float]:
    """Shortest (moving_time_s, accel_time_s) of a rest-to-rest trapezoid over s = 0 → 1.

    Triangular when the velocity limit is never reached (accel_time = moving_time / 2).
    """
    if math.isinf(s_velocity) and math.isinf(s_accel):
        return 0.0, 0.0
    if s_velocity * s_velocity / s_accel >= 1.0:
        accel_time_s = math.sqrt(1.0 / s_accel)
        return 2.0 * accel_time_s, accel_time_s
    accel_time_s = s_velocity / s_accel
    return 1.0 / s_velocity + accel_time_s, accel_time_s


def feasible_accel_times(moving_time_s: float, s_velocity: float, s_accel: float) -> tuple[float, float] | None:
    """The interval of accel_time_s that keeps s(t) within its limits for this moving_time_s, or None.

    Peak velocity 1 / (T - Ta) ≤ V  ⇔  Ta ≤ T - 1/V; peak acceleration 1 / (Ta (T - Ta)) ≤ A  ⇔  Ta
    between the roots of Ta² - T·Ta + 1/A; and Ta ≤ T/2 (the ramps cannot overlap).
    """
    total = moving_time_s
    upper = total / 2.0
    if not math.isinf(s_velocity):
        upper = min(upper, total - 1.0 / s_velocity)
    lower = 0.0
    if not math.isinf(s_accel):
        discriminant = total * total - 4.0 / s_accel
        if discriminant < -_FEASIBILITY_RTOL * total * total:
            return None
        lower = (total - math.sqrt(max(discriminant, 0.0))) / 2.0
    if lower > upper * (1.0 + _FEASIBILITY_RTOL) + 1e-12:
        return None
    return lower, max(lower, upper)


def time_joint_move(
    delta_rad: np.ndarray,
    velocity_limit_rad_s: np.ndarray,
    accel_limit_rad_s2: np.ndarray,
    moving_time_s: float | None = None,
    accel_time_s: float | None = None,
) -> MoveTiming:
    """Choose (moving_time_s, accel_time_s) for a synchronised move of delta_rad within the limits.

    moving_time_s None: the shortest time the limits allow. Given but too short: stretched to that
    minimum. accel_time_s None: a third of the move (smooth and not too peaky), moved into the
    feasible range; given: kept if feasible, else clamped to the nearest feasible value.
    """
    delta_rad = np.asarray(delta_rad, dtype=float)
    requested_moving = _check_duration("moving_time_s", moving_time_s)
    requested_accel = _check_duration("accel_time_s", accel_time_s)
    s_velocity, s_accel = scalar_limits(delta_rad, np.asarray(velocity_limit_rad_s, float), np.asarray(accel_limit_rad_s2, float))
    min_moving, min_accel = minimum_time(s_velocity, s_accel)
    notes: list[str] = []

    if min_moving == 0.0:  # nothing moves
        total = requested_moving if requested_moving is not None else 0.0
        ramp = min(requested_accel if requested_accel is not None else total / 3.0, total / 2.0)
        if requested_accel is not None and ramp != requested_accel:
            notes.append(f"accel_time_s {requested_accel:.3f} → {ramp:.3f} s (at most half of moving_time_s)")
        zeros = np.zeros_like(delta_rad)
        return MoveTiming(total, ramp, requested_moving, requested_accel, tuple(notes), zeros, zeros)

    if requested_moving is None:
        total = min_moving
    elif requested_moving < min_moving:
        total = min_moving
        notes.append(
            f"moving_time_s {requested_moving:.3f} → {min_moving:.3f} s (the joint limits allow no faster move)"
        )
    else:
        total = requested_moving

    interval = feasible_accel_times(total, s_velocity, s_accel)
    if interval is None:  # only at total == min_moving with rounding: use the analytic optimum
        interval = (min_accel, min_accel)
    low, high = interval
    if requested_accel is None:
        ramp = min(max(total / 3.0 if requested_moving is not None else min_accel, low), high)
    else:
        ramp = min(max(requested_accel, low), high)
        if not math.isclose(ramp, requested_accel, rel_tol=1e-9, abs_tol=1e-12):
            notes.append(
                f"accel_time_s {requested_accel:.3f} → {ramp:.3f} s (feasible range {low:.3f}…{high:.3f} s "
                f"for moving_time_s {total:.3f})"
            )
    peak_velocity, peak_accel = _trapezoid_peaks(delta_rad, total, ramp)
    return MoveTiming(total, ramp, requested_moving, requested_accel, tuple(notes), peak_velocity, peak_accel)


def _trapezoid_peaks(delta_rad, moving_time_s: float, accel_time_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-joint (peak velocity, peak acceleration) of a synchronised trapezoid of delta_rad."""
    cruise = moving_time_s - accel_time_s
    magnitude = np.abs(np.asarray(delta_rad, dtype=float))
    peak_accel = magnitude / (accel_time_s * cruise) if accel_time_s > 0 else np.where(magnitude > 0, np.inf, 0.0)
    return magnitude / cruise, peak_accel


def trapezoid_profile(t_s: np.ndarray, moving_time_s: float, accel_time_s: float) -> np.ndarray:
    """s(t) ∈ [0, 1] of a rest-to-rest trapezoid (constant acceleration ramps, constant cruise)."""
    t = np.clip(np.asarray(t_s, dtype=float), 0.0, moving_time_s)
    total, ramp = moving_time_s, accel_time_s
    if total <= 0.0:
        return np.ones_like(t)
    if ramp <= 1e-9 * total:  # no ramp (only used for moves that do not move)
        return t / total
    peak_velocity = 1.0 / (total - ramp)
    accel = peak_velocity / ramp
    return np.where(
        t < ramp,
        0.5 * accel * t * t,
        np.where(
            t <= total - ramp,
            0.5 * accel * ramp * ramp + peak_velocity * (t - ramp),
            1.0 - 0.5 * accel * (total - t) ** 2,
        ),
    )


def sample_times(duration_s: float, rate_hz: float = DEFAULT_RATE_HZ) -> np.ndarray:
    """Uniform sample times 0 … duration_s at no less than rate_hz (at least two samples)."""
    if not math.isfinite(rate_hz) or rate_hz <= 0:
        raise InvalidInput(f"rate_hz must be > 0, got {rate_hz}")
    count = max(1, math.ceil(duration_s * rate_hz - 1e-9))
    return np.linspace(0.0, duration_s, count + 1) if duration_s > 0 else np.array([0.0, 1.0 / rate_hz])


def check_joint_positions(name: str, q_rad, lower_rad: np.ndarray, upper_rad: np.ndarray, joint_names=None) -> np.ndarray:
    """q as a (dof,) vector inside [lower, upper]; InvalidInput naming the joint otherwise."""
    q = _as_joint_vector(name, q_rad, len(lower_rad))
    outside = np.flatnonzero((q < lower_rad) | (q > upper_rad))
    if outside.size:
        index = int(outside[0])
        joint = joint_names[index] if joint_names is not None else f"joint {index}"
        raise InvalidInput(
            f"{name}: {joint} = {q[index]:.4f} rad is outside its limits [{lower_rad[index]:.4f}, {upper_rad[index]:.4f}]"
        )
    return q


def on_sample_grid(timing: MoveTiming, delta_rad: np.ndarray, rate_hz: float) -> MoveTiming:
    """A move at the limits (no duration asked, or one stretched to the shortest) lengthened to whole sample
    periods, the ramps kept: the servos interpolate the samples linearly, and only on a grid of whole periods
    does every window of two periods see at most the plan's acceleration (a 9.85 ms grid showed 1.005x)."""
    at_limits = timing.requested_moving_time_s is None or timing.moving_time_s > timing.requested_moving_time_s
    total = math.ceil(timing.moving_time_s * rate_hz - 1e-3) / rate_hz  # within 0.1 % of a period: on the grid
    if not at_limits or timing.moving_time_s <= 0.0 or total <= timing.moving_time_s or timing.accel_time_s <= 0.0:
        return timing
    peak_velocity, peak_accel = _trapezoid_peaks(delta_rad, total, timing.accel_time_s)
    return replace(timing, moving_time_s=total, peak_velocity_rad_s=peak_velocity, peak_accel_rad_s2=peak_accel)


def plan_joint_move_timed(
    q_start_rad,
    q_goal_rad,
    arm,
    moving_time_s: float | None = None,
    accel_time_s: float | None = None,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> tuple[JointTrajectory, MoveTiming]:
    """Like plan_joint_move, also returning the MoveTiming (what was clamped)."""
    lower, upper = np.asarray(arm.lower_rad, float), np.asarray(arm.upper_rad, float)
    names = getattr(arm, "joint_names", None)
    q_measured = check_joint_positions(
        "q_start", q_start_rad, lower - START_TOLERANCE_RAD, upper + START_TOLERANCE_RAD, names
    )
    q_start = np.clip(q_measured, lower, upper)
    q_goal = check_joint_positions("q_goal", q_goal_rad, lower, upper, names)
    delta = q_goal - q_start
    timing = time_joint_move(
        delta,
        np.asarray(arm.velocity_limit_rad_s, float) * LIMIT_MARGIN,
        planning_accel_rad_s2(arm),
        moving_time_s,
        accel_time_s,
    )
    timing = on_sample_grid(timing, delta, rate_hz)
    times = sample_times(timing.moving_time_s, rate_hz)
    s = trapezoid_profile(times, timing.moving_time_s, timing.accel_time_s)
    positions = q_start[None, :] + s[:, None] * delta[None, :]
    positions[-1] = q_goal  # exact end point, no rounding drift
    if np.any(q_start != q_measured):
        moved = ", ".join(
            f"{names[i] if names is not None else f'joint {i}'} {q_measured[i]:.4f} → {q_start[i]:.4f}"
            for i in np.flatnonzero(q_start != q_measured)
        )
        timing = replace(timing, clamped=(*timing.clamped, f"start moved onto the joint limits: {moved} rad"))
    return JointTrajectory(times_s=times, positions_rad=positions), timing


def plan_joint_move(
    q_start_rad,
    q_goal_rad,
    arm,
    moving_time_s: float | None = None,
    accel_time_s: float | None = None,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> JointTrajectory:
    """A synchronised trapezoidal move q_start → q_goal sampled at ≥ rate_hz, within arm's limits.

    arm: anything with lower_rad, upper_rad, velocity_limit_rad_s, accel_limit_rad_s2 (shape (dof,)),
    e.g. armlab.kinematics.load_arm("rx200"). Raises ValueError (naming the joint) for a wrong shape,
    a non-finite value or a position outside the limits. See plan_joint_move_timed for the report.
    """
    return plan_joint_move_timed(q_start_rad, q_goal_rad, arm, moving_time_s, accel_time_s, rate_hz)[0]


def retime_path(
    positions_rad: np.ndarray,
    path_s: np.ndarray,
    velocity_limit_rad_s: np.ndarray,
    accel_limit_rad_s2: np.ndarray,
) -> float:
    """Scale factor ≥ 1 by which to slow a sampled path so its finite differences obey the limits.

    positions_rad (N, dof) sampled at times path_s (N,). Velocity scales as 1/k and acceleration as
    1/k², so k = max(1, max v/v_limit, sqrt(max a/a_limit)).
    """
    dt = np.diff(path_s)
    velocity = np.diff(positions_rad, axis=0) / dt[:, None]
    ratio = float(np.max(np.abs(velocity) / velocity_limit_rad_s[None, :])) if velocity.size else 0.0
    if positions_rad.shape[0] >= 3:
        mid_dt = 0.5 * (dt[1:] + dt[:-1])
        accel = np.diff(velocity, axis=0) / mid_dt[:, None]
        ratio = max(ratio, math.sqrt(float(np.max(np.abs(accel) / accel_limit_rad_s2[None, :]))))
    return max(1.0, ratio)
