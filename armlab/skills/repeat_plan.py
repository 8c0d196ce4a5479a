"""Planning one cycle of a taught program for repeat: stops, blended runs, gripper steps, dwells, all checked.

A cycle starts at rest on waypoint 1 with its gripper command applied and ends back there: moves through
the waypoints, then the closing move from the last waypoint back to the first. The arm stops at a
waypoint when something happens there (a gripper change, a dwell, the next waypoint is a gripper step at
the same pose) and at the last one; it passes through the others on a blended, jerk-limited run
(armlab.motion.blend). Every waypoint and every run is checked by the station before anything moves
(joint, velocity and acceleration limits, the table, the workspace box); a blended run that fails is
re-planned to stop at each of its waypoints, and a segment that still fails refuses the program, named.
Each step carries its planned duration, so the job can pace by absolute deadlines.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from armlab.errors import InvalidInput
from armlab.motion.blend import Limits, Run, arm_limits, plan_run
from armlab.motion.safety import UnsafeTrajectory
from armlab.store import Program, Waypoint

SAME_POSE_RAD = 1e-6  # waypoints this close are the same pose (a gripper step or a dwell there)


@dataclass(frozen=True)
class RepeatSettings:
    """How repeat moves between the taught waypoints (seconds, fractions of full speed)."""

    ease_in_speed_fraction: float = 0.25  # ease in from the current pose, and return home, at most this fast
    gripper_time_s: float = 1.0  # time budget of a gripper step (the arm settles, the fingers close or open)
    jerk_factor_per_s: float = 30.0  # jerk limit = acceleration limit × this (150 rad/s³ on the rx200)
    limit_margin: float = 0.98  # plans stay this fraction inside the velocity and acceleration limits
    rate_hz: float = 100.0  # trajectory samples per second


@dataclass
class Step:
    """One step of a cycle: a move run through `points` (waypoint indices, the first is where it starts),
    a gripper action at `waypoint`, or a dwell there. offset_s/duration_s: its place in the cycle."""

    kind: str  # "move" | "gripper" | "dwell"
    waypoint: int
    offset_s: float = 0.0
    duration_s: float = 0.0
    points: tuple[int, ...] = ()
    run: Run | None = None
    action: str | None = None
    closing: bool = False  # the return to waypoint 1 at the end of a cycle (not after the last cycle)


@dataclass
class CyclePlan:
    """A planned cycle at one speed: its steps, the full cycle time and the last cycle's (no closing steps)."""

    speed_percent: float
    steps: list[Step]
    cycle_s: float
    last_cycle_s: float
    blended_runs: int
    runs: int
    notes: list[str] = field(default_factory=list)


def same_pose(a: Waypoint, b: Waypoint) -> bool:
    return float(np.max(np.abs(np.subtract(a.joints_rad, b.joints_rad)))) <= SAME_POSE_RAD


def check_waypoints(station, waypoints) -> None:
    """Every waypoint inside the joint limits, above the table and inside the workspace box, the fingers clear of the
    board and the arm clear of itself (ValueError / UnsafeTrajectory naming the waypoint, 1-based)."""
    if not waypoints:
        raise InvalidInput("the program has no waypoints: record at least one")
    station.check_poses([waypoint.joints_rad for waypoint in waypoints])


def station_limits(station, settings: RepeatSettings) -> Limits:
    return arm_limits(station.model, settings.limit_margin, settings.jerk_factor_per_s)


def tick_s(station) -> float:
    """The controller's period when known (the simulation), so step durations land on control ticks."""
    return float(getattr(station.sim, "control_period_s", 0.0) or 0.0) if station.sim is not None else 0.0


def checked_run(station, points: np.ndarray, labels: list[int], limits: Limits, minimum_s, settings: RepeatSettings,
                allow_blend: bool = True) -> Run:
    """A run through `points` that passes the station's motion check: blended if that passes, else stopping
    at each waypoint; UnsafeTrajectory naming the failing segment (waypoints `labels`, 1-based) otherwise."""
    tick = tick_s(station)
    if allow_blend and len(points) > 2:
        run = plan_run(points, limits, minimum_s=minimum_s, tick_s=tick, rate_hz=settings.rate_hz)
        try:
            station.check_motion(run.trajectory)
            return run
        except UnsafeTrajectory:
            pass
    run = plan_run(points, limits, stop_everywhere=True, minimum_s=minimum_s, tick_s=tick, rate_hz=settings.rate_hz)
    try:
        station.check_motion(run.trajectory)
        return run
    except UnsafeTrajectory:
        pass
    for k in range(1, len(points)):  # name the segment that fails
        segment = plan_run(points[k - 1 : k + 1], limits, tick_s=tick, rate_hz=settings.rate_hz)
        try:
            station.check_motion(segment.trajectory)
        except UnsafeTrajectory as error:
            raise UnsafeTrajectory(f"segment from {_label(labels[k - 1])} to {_label(labels[k])}: {error}") from None
    raise UnsafeTrajectory(f"the move through waypoints {', '.join(_label(i) for i in labels)} fails the motion check")


def _label(index: int) -> str:
    return "the current pose" if index < 0 else ("home" if index == 10**9 else f"waypoint {index + 1}")


def plan_cycle(station, program: Program, speed_percent: float, settings: RepeatSettings = RepeatSettings()) -> CyclePlan:
    """The checked plan of one cycle of `program` at `speed_percent` (ValueError/UnsafeTrajectory: refused)."""
    waypoints = list(program.waypoints)
    check_waypoints(station, waypoints)
    speed = float(speed_percent) / 100.0
    limits = station_limits(station, settings).scaled(speed)
    steps: list[Step] = []

    def stop_actions(k: int, gripper_before: str, closing: bool = False) -> None:
        if waypoints[k].gripper != gripper_before:
            steps.append(Step("gripper", k, duration_s=settings.gripper_time_s, action=waypoints[k].gripper, closing=closing))
        if waypoints[k].dwell_s > 0 and not closing:
            steps.append(Step("dwell", k, duration_s=waypoints[k].dwell_s))

    def add_run(indices: list[int], closing: bool = False) -> None:
        points = np.array([waypoints[i].joints_rad for i in indices])
        minimum = [None] + [
            (waypoints[i].moving_time_s / speed if waypoints[i].moving_time_s else None) for i in indices[1:]
        ]
        run = checked_run(station, points, indices, limits, minimum, settings)
        steps.append(Step("move", indices[-1], duration_s=run.duration_s, points=tuple(indices), run=run, closing=closing))

    n = len(waypoints)
    if waypoints[0].dwell_s > 0:
        steps.append(Step("dwell", 0, duration_s=waypoints[0].dwell_s))
    gripper, run_points = waypoints[0].gripper, [0]
    for k in range(1, n):
        if same_pose(waypoints[k], waypoints[run_points[-1]]):
            if len(run_points) > 1:
                add_run(run_points)
            stop_actions(k, gripper)
            gripper, run_points = waypoints[k].gripper, [k]
            continue
        run_points.append(k)
        next_is_step = k + 1 < n and same_pose(waypoints[k + 1], waypoints[k])
        if k == n - 1 or next_is_step or waypoints[k].gripper != gripper or waypoints[k].dwell_s > 0:
            add_run(run_points)
            stop_actions(k, gripper)
            gripper, run_points = waypoints[k].gripper, [k]
    last_cycle_s = sum(step.duration_s for step in steps)
    if not same_pose(waypoints[-1], waypoints[0]):
        add_run([n - 1, 0], closing=True)
    if waypoints[0].gripper != gripper:
        steps.append(Step("gripper", 0, duration_s=settings.gripper_time_s, action=waypoints[0].gripper, closing=True))
    offset = 0.0
    for step in steps:
        step.offset_s = offset
        offset += step.duration_s
    if offset <= 0:
        raise InvalidInput("the program does not move: it needs two different poses, a gripper change or a dwell to repeat")
    moves = [step for step in steps if step.kind == "move"]
    return CyclePlan(
        speed_percent=float(speed_percent),
        steps=steps,
        cycle_s=offset,
        last_cycle_s=last_cycle_s,
        blended_runs=sum(1 for step in moves if step.run.blended),
        runs=len(moves),
    )


def plan_transfer(station, q_from, q_to, speed_percent: float, settings: RepeatSettings, labels=(-1, 0)) -> Run:
    """A checked rest-to-rest move at min(speed, the ease-in speed): the ease-in to waypoint 1, the way home."""
    fraction = min(float(speed_percent) / 100.0, settings.ease_in_speed_fraction)
    limits = station_limits(station, settings).scaled(fraction)
    points = np.array([np.asarray(q_from, dtype=float), np.asarray(q_to, dtype=float)])
    return checked_run(station, points, list(labels), limits, None, settings, allow_blend=False)


def plan_ease_in(station, q_from, q_to, speed_percent: float, settings: RepeatSettings, labels=(-1, 0)):
    """The ease-in (or any transfer) as (points, run, labels): straight in joint space when that passes the
    motion check, else by way of home (stopping there), e.g. from the sleep pose, whose straight path to a
    low waypoint can sweep through the table; the straight path's refusal when neither passes."""
    q_from, q_to = np.asarray(q_from, dtype=float), np.asarray(q_to, dtype=float)
    try:
        return [q_from, q_to], plan_transfer(station, q_from, q_to, speed_percent, settings, labels), list(labels)
    except UnsafeTrajectory as direct:
        home = np.asarray(station.model.home_rad, dtype=float)
        if np.allclose(home, q_from) or np.allclose(home, q_to):
            raise
        fraction = min(float(speed_percent) / 100.0, settings.ease_in_speed_fraction)
        limits = station_limits(station, settings).scaled(fraction)
        via = [labels[0], HOME_LABEL, labels[1]]
        try:
            run = checked_run(station, np.array([q_from, home, q_to]), via, limits, None, settings, allow_blend=False)
        except UnsafeTrajectory:
            raise direct from None
        return [q_from, home, q_to], run, via


HOME_LABEL = 10**9
