"""Time-optimal, jerk-limited joint trajectories through waypoints (ruckig), for repeating taught programs.

A *run* goes from one stop to the next through waypoints it does not stop at. Each segment between two
waypoints is one ruckig trajectory (time-optimal for its boundary states, every joint within its
velocity, acceleration and jerk limits, all joints synchronised); at a waypoint the arm passes with a
velocity chosen per joint (about the neighbouring segments' mean velocity when both move the joint the
same way, else 0) and zero acceleration, so the motion is smooth and never has to brake to
rest at a pass-through waypoint. `stop_everywhere=True` gives the rest-to-rest run (every waypoint a
stop). The speed override scales the limits as time scaling does: velocity × s, acceleration × s²,
jerk × s³. With tick_s > 0 every segment lasts a whole number of ticks (the controller's period), so
absolute deadlines land on control ticks. Pure functions: no device calls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput, PlanRefused
from armlab.motion.planning_limits import planning_accel_rad_s2

DEFAULT_JERK_FACTOR_PER_S = 30.0  # jerk limit = acceleration limit × this (rad/s³ per rad/s²)
DEFAULT_RATE_HZ = 100.0


@dataclass(frozen=True)
class Limits:
    """Per-joint velocity (rad/s), acceleration (rad/s²) and jerk (rad/s³) limits, shape (dof,) each."""

    velocity_rad_s: np.ndarray
    accel_rad_s2: np.ndarray
    jerk_rad_s3: np.ndarray

    def scaled(self, speed_fraction: float) -> Limits:
        """The limits of a run at `speed_fraction` (0 < s ≤ 1) of full speed (time scaling: v·s, a·s², j·s³)."""
        s = float(speed_fraction)
        if not 0.0 < s <= 1.0:
            raise InvalidInput(f"speed fraction must be in (0, 1], got {speed_fraction!r}")
        return Limits(self.velocity_rad_s * s, self.accel_rad_s2 * s * s, self.jerk_rad_s3 * s**3)


def arm_limits(model, margin: float = 0.98, jerk_factor_per_s: float = DEFAULT_JERK_FACTOR_PER_S) -> Limits:
    """The arm model's velocity limits × margin (so sampled finite differences stay inside them), the acceleration it
    is planned at (armlab.motion.planning_limits, × margin when that is smaller) and a jerk limit of jerk_factor_per_s
    × that acceleration."""
    velocity = np.asarray(model.velocity_limit_rad_s, dtype=float) * margin
    accel = planning_accel_rad_s2(model, margin)
    return Limits(velocity, accel, accel * jerk_factor_per_s)


@dataclass(frozen=True)
class Run:
    """A planned run: the sampled trajectory and when it reaches each of its waypoints (arrival_s[0] = 0
    is the start). blended: whether it passes through intermediate waypoints without stopping."""

    trajectory: JointTrajectory
    arrival_s: tuple[float, ...]
    blended: bool

    @property
    def duration_s(self) -> float:
        return self.trajectory.duration_s


def overshoot_free_accel(velocity_rad_s, accel_rad_s2, limits: Limits) -> np.ndarray:
    """The start acceleration cut so that no plan from (velocity, accel) need pass the velocity limit: an
    acceleration still pushing a joint toward its limit takes a²/2j more velocity to bring to zero at the jerk
    limit, so it may be at most sqrt(2·j·(v_max − |v|)) (0 at or above the limit). Velocity is kept (continuity);
    only the acceleration steps, by less than the acceleration limit. Without this a takeover at cruise speed while
    still accelerating was planned ~0.7 % over the waist's velocity limit and refused."""
    velocity = np.asarray(velocity_rad_s, dtype=float)
    accel = np.asarray(accel_rad_s2, dtype=float)
    room = np.maximum(limits.velocity_rad_s - np.abs(velocity), 0.0)
    allowed = np.sqrt(2.0 * limits.jerk_rad_s3 * room)
    outward = (accel * velocity) > 0.0
    return np.where(outward, np.sign(accel) * np.minimum(np.abs(accel), allowed), accel)


def _ruckig_segment(q0, v0, a0, q1, v1, limits: Limits, minimum_s: float | None, tick_s: float):
    """One ruckig trajectory from (q0, v0, a0) to (q1, v1, 0); PlanRefused if ruckig finds none. a0 is cut where it
    would carry a joint past its velocity limit (overshoot_free_accel)."""
    from ruckig import DurationDiscretization, InputParameter, Result, Ruckig, Trajectory

    dof = len(q0)
    a0 = overshoot_free_accel(v0, a0, limits)
    otg = Ruckig(dof, tick_s) if tick_s > 0 else Ruckig(dof)
    inp = InputParameter(dof)
    inp.current_position, inp.current_velocity, inp.current_acceleration = list(q0), list(v0), list(a0)
    inp.target_position, inp.target_velocity, inp.target_acceleration = list(q1), list(v1), [0.0] * dof
    inp.max_velocity = list(limits.velocity_rad_s)
    inp.max_acceleration = list(limits.accel_rad_s2)
    inp.max_jerk = list(limits.jerk_rad_s3)
    if tick_s > 0:
        inp.duration_discretization = DurationDiscretization.Discrete
    if minimum_s:
        inp.minimum_duration = float(minimum_s)
    trajectory = Trajectory(dof)
    result = _calculate(otg, inp, trajectory)
    if result not in (Result.Working, Result.Finished):
        raise PlanRefused(f"no jerk-limited trajectory between these states ({result.name})")
    return trajectory


def _calculate(otg, inp, trajectory):
    """ruckig's calculate, its own errors (an invalid input, a result code its Python enum does not know such as
    -101, a duration past its numerical range) as a PlanRefused that says where they come from."""
    try:
        return otg.calculate(inp, trajectory)
    except Exception as error:  # noqa: BLE001 - the library raises ValueError, RuntimeError or its own types
        first_line = (str(error).strip().splitlines() or [""])[0]
        raise PlanRefused(f"the trajectory library (ruckig) found no trajectory: {type(error).__name__}: {first_line}") from None


def _rest_to_rest_time(delta: np.ndarray, limits: Limits) -> float:
    """Lower bound of a rest-to-rest move's time (slowest joint's trapezoid), for choosing pass velocities."""
    longest = 0.0
    for d, v, a in zip(np.abs(delta), limits.velocity_rad_s, limits.accel_rad_s2):
        if d <= 0:
            continue
        longest = max(longest, 2.0 * math.sqrt(d / a) if d <= v * v / a else d / v + v / a)
    return longest


def pass_velocities(points: np.ndarray, limits: Limits, minimum_s=None) -> np.ndarray:
    """Velocity (m, dof) at each point of a run: 0 at both ends and wherever a joint reverses or rests,
    else the mean of the neighbouring segments' mean velocities (each segment timed by its slowest joint at
    full velocity, or its minimum_s if longer), capped by the velocity limit and by what the shorter
    neighbour can reach from rest, sqrt(|d| · a_max)."""
    m, dof = points.shape
    velocities = np.zeros((m, dof))
    deltas = np.diff(points, axis=0)
    durations = []
    for index, delta in enumerate(deltas):
        cruise_s = float(np.max(np.abs(delta) / limits.velocity_rad_s))  # at full velocity, no ramps
        duration = max(cruise_s, (minimum_s[index + 1] if minimum_s else 0.0) or 0.0)
        durations.append(duration)
    for k in range(1, m - 1):
        before, after = deltas[k - 1], deltas[k]
        if durations[k - 1] <= 0 or durations[k] <= 0:
            continue
        same_way = (np.sign(before) == np.sign(after)) & (before != 0) & (after != 0)
        mean = 0.5 * (np.abs(before) / durations[k - 1] + np.abs(after) / durations[k])
        reach = np.sqrt(np.minimum(np.abs(before), np.abs(after)) * limits.accel_rad_s2)
        velocities[k] = np.where(same_way, np.sign(before) * np.minimum(np.minimum(mean, reach), limits.velocity_rad_s), 0.0)
    return velocities


def _plan_run_once(
    points_rad,
    limits: Limits,
    *,
    start_velocity=None,
    start_accel=None,
    stop_everywhere: bool = False,
    minimum_s=None,
    tick_s: float = 0.0,
    rate_hz: float = DEFAULT_RATE_HZ,
    pass_scale: float = 1.0,
) -> Run:
    """One run with the pass-through velocities × pass_scale (see plan_run)."""
    points = np.asarray(points_rad, dtype=float)
    if points.ndim != 2 or points.shape[0] < 2:
        raise InvalidInput("a run needs at least two points")
    m, dof = points.shape
    passes = np.zeros((m, dof)) if stop_everywhere else pass_scale * pass_velocities(points, limits, minimum_s)
    velocity = np.zeros(dof) if start_velocity is None else np.asarray(start_velocity, dtype=float)
    accel = np.zeros(dof) if start_accel is None else np.asarray(start_accel, dtype=float)
    times, samples, arrivals = [0.0], [points[0].copy()], [0.0]
    offset = 0.0
    for index in range(1, m):
        segment = _ruckig_segment(
            points[index - 1], velocity, accel, points[index], passes[index], limits,
            minimum_s[index] if minimum_s else None, tick_s,
        )
        duration = float(segment.duration)
        if duration > 0:
            count = max(1, math.ceil(duration * rate_hz - 1e-9))
            for t in np.linspace(0.0, duration, count + 1)[1:]:
                position, _, _ = segment.at_time(float(t))
                times.append(offset + float(t))
                samples.append(np.asarray(position, dtype=float))
            samples[-1] = points[index].copy()  # exact arrival
        offset += duration
        arrivals.append(offset)
        velocity, accel = passes[index], np.zeros(dof)
    if len(times) == 1:  # nothing moves: a two-sample trajectory standing still
        times.append(1.0 / rate_hz)
        samples.append(points[-1].copy())
    return Run(JointTrajectory(np.asarray(times), np.asarray(samples)), tuple(arrivals), bool(np.any(passes)))


PASS_SCALES = (1.0, 0.6, 0.3)  # pass-through velocities tried (× the heuristic's); the quickest run wins


def plan_run(
    points_rad,
    limits: Limits,
    *,
    start_velocity=None,
    start_accel=None,
    stop_everywhere: bool = False,
    minimum_s=None,
    tick_s: float = 0.0,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> Run:
    """A run through points_rad (m ≥ 2, dof), ending at rest on the last point. The first point is the
    start; start_velocity/start_accel (default rest) let a run continue a motion in progress (a speed
    change). minimum_s[i]: the least time of the segment into point i (a waypoint's moving_time_s; [0]
    unused). Blended runs try the pass-through velocities at a few scales (PASS_SCALES) and keep the
    quickest: per-segment planning with zero acceleration at the waypoints can be slower with the
    heuristic's full velocities on short segments. PlanRefused if ruckig fails."""
    options = dict(start_velocity=start_velocity, start_accel=start_accel, minimum_s=minimum_s, tick_s=tick_s, rate_hz=rate_hz)
    if stop_everywhere or len(points_rad) <= 2:
        return _plan_run_once(points_rad, limits, stop_everywhere=stop_everywhere, **options)
    runs = [_plan_run_once(points_rad, limits, pass_scale=scale, **options) for scale in PASS_SCALES]
    return min(runs, key=lambda run: run.duration_s)


def plan_stop(position_rad, velocity_rad_s, accel_rad_s2, limits: Limits, rate_hz: float = DEFAULT_RATE_HZ) -> JointTrajectory:
    """The quickest jerk-limited stop from a moving state (pause): every joint brakes to rest."""
    from ruckig import ControlInterface, InputParameter, Result, Ruckig, Trajectory

    dof = len(position_rad)
    otg, inp = Ruckig(dof), InputParameter(dof)
    inp.control_interface = ControlInterface.Velocity
    inp.current_position = [float(v) for v in position_rad]
    inp.current_velocity = [float(v) for v in velocity_rad_s]
    inp.current_acceleration = [float(v) for v in overshoot_free_accel(velocity_rad_s, accel_rad_s2, limits)]
    inp.target_velocity, inp.target_acceleration = [0.0] * dof, [0.0] * dof
    inp.max_velocity = list(limits.velocity_rad_s)
    inp.max_acceleration = list(limits.accel_rad_s2)
    inp.max_jerk = list(limits.jerk_rad_s3)
    trajectory = Trajectory(dof)
    if _calculate(otg, inp, trajectory) not in (Result.Working, Result.Finished):
        raise PlanRefused("no stopping trajectory")
    duration = max(float(trajectory.duration), 1.0 / rate_hz)
    count = max(1, math.ceil(duration * rate_hz - 1e-9))
    times = np.linspace(0.0, duration, count + 1)
    samples = [np.asarray(trajectory.at_time(float(min(t, trajectory.duration)))[0], dtype=float) for t in times]
    return JointTrajectory(times, np.asarray(samples))


def reference_state(trajectory: JointTrajectory, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(position, velocity, acceleration) of a sampled trajectory at t_s, by finite differences of the
    samples around it (zero velocity and acceleration past the end)."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    if t_s >= times[-1] or len(times) < 3:
        return positions[-1].copy(), np.zeros(positions.shape[1]), np.zeros(positions.shape[1])
    t_s = max(0.0, t_s)
    position = trajectory.sample(t_s)
    i = int(np.clip(np.searchsorted(times, t_s, side="right") - 1, 1, len(times) - 2))
    v_before = (positions[i] - positions[i - 1]) / (times[i] - times[i - 1])
    v_after = (positions[i + 1] - positions[i]) / (times[i + 1] - times[i])
    accel = (v_after - v_before) / (0.5 * (times[i + 1] - times[i - 1]))
    return position, v_after, accel
