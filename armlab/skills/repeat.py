"""Repeat a taught program as a job: N cycles or until stopped, paced by absolute deadlines, pausable.

Before anything moves the whole cycle, the ease-in from the current pose and the way home are planned
and checked (repeat_plan.py); a program that fails is refused with the reason. The job then eases in
to waypoint 1 at a safe speed, and runs the cycle's steps each at its deadline on the motion clock
(anchor + cycle × cycle time + the step's offset), so 100 cycles take 100 × one cycle with no drift.
The job's RunControl (pause, resume, step, speed) is read at every wait: a pause brakes to rest on a
jerk-limited stop, resume re-plans from where the arm stopped through the waypoints that run had left,
step goes to the next waypoint only (while paused the job offers that step's planner through its RunControl, so the
step can be planned and shown first and then run exactly as shown: Station.plan_job_step), and a speed change re-plans
the rest of the run from the motion in progress; each of these re-anchors the deadlines. Progress (cycle, waypoint, time left, speed) is in
job.extra["repeat"]; commanded and measured joints of the last cycle are kept in the control's trace.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from armlab.errors import PLAN_REFUSALS, CommandRefused, InvalidInput, PlanRefused
from armlab.motion.blend import Limits, Run, plan_run, plan_stop
from armlab.skills.repeat_plan import (
    HOME_LABEL,
    CyclePlan,
    RepeatSettings,
    Step,
    checked_run,
    plan_cycle,
    plan_ease_in,
    plan_transfer,
    station_limits,
    tick_s,
)
from armlab.station.core import Station
from armlab.station.job_control import RunControl, checked_speed_percent
from armlab.station.jobs import Job, JobContext

MAX_CYCLES = 100_000
WAIT_LIMIT_S = 3600.0  # one wait while paused; the job waits again after it
TRACE_RATE_HZ = 50.0
TRACE_MAX_SAMPLES = 30_000  # 10 min at TRACE_RATE_HZ: a cycle paused for hours keeps its first 10 min


class CycleTrace:
    """Commanded and measured joints over the last complete cycle (and the one in progress), for plots."""

    def __init__(self, joint_names) -> None:
        self.joint_names = tuple(joint_names)
        self._lock = threading.Lock()
        self._current: list[tuple] = []
        self._last: list[tuple] = []
        self._last_cycle = 0
        self._cycle = 0

    def start_cycle(self, cycle: int) -> None:
        with self._lock:
            if self._current and self._cycle >= 1:  # the ease-in before cycle 1 is not a cycle
                self._last, self._last_cycle = self._current, self._cycle
            self._current, self._cycle = [], cycle

    def add(self, t_s: float, commanded, measured) -> None:
        with self._lock:
            if len(self._current) >= TRACE_MAX_SAMPLES or (self._current and t_s - self._current[-1][0] < 1.0 / TRACE_RATE_HZ):
                return
            self._current.append((float(t_s), tuple(float(v) for v in commanded), tuple(float(v) for v in measured)))

    def snapshot(self) -> dict:
        """{cycle, complete, joint_names, samples: [[t_s (from the cycle's start), commanded..., measured...]]}."""
        with self._lock:
            rows, cycle, complete = (self._last, self._last_cycle, True) if self._last else (list(self._current), self._cycle, False)
        t0 = rows[0][0] if rows else 0.0
        return {
            "cycle": cycle,
            "complete": complete,
            "joint_names": list(self.joint_names),
            "samples": [[round(t - t0, 6), *commanded, *measured] for t, commanded, measured in rows],
        }


class _Runner:
    """The repeat job's loop (one instance per job, used only on the job's thread)."""

    def __init__(self, station: Station, ctx: JobContext, program, cycles: int | None, control: RunControl,
                 settings: RepeatSettings, trace: CycleTrace, plans: dict[float, CyclePlan] | None = None,
                 ease_in: tuple | None = None) -> None:
        self.station, self.ctx, self.program, self.cycles = station, ctx, program, cycles
        self.ease_in = ease_in  # (points, run, labels) planned already (a plan shown, then executed), else planned here
        self.control, self.settings, self.trace = control, settings, trace
        self.plans: dict[float, CyclePlan] = {} if plans is None else plans
        self.speed_cap, self.run_speed = 100.0, control.speed_percent
        self.plan = self._plan(control.speed_percent)
        self.anchor_s = 0.0
        self.cycle = 0
        self.cycle_starts_s: list[float] = []
        self.current: tuple[object, float] | None = None  # (commanded trajectory, its start time) for the trace
        self.waypoint = 0
        self.phase = "ease in"
        self.speed_seen = control.speed_percent
        self.eps = max(1e-9, 0.5 * tick_s(station))  # clock comparisons: half a control tick

    # Planning and waiting -------------------------------------------------------------------------

    def _plan(self, speed_percent: float) -> CyclePlan:
        if speed_percent not in self.plans:
            self.plans[speed_percent] = plan_cycle(self.station, self.program, speed_percent, self.settings)
        return self.plans[speed_percent]

    def clock(self) -> float:
        return self.station.clock_s()

    def _sample(self) -> None:
        if self.current is None:
            return
        trajectory, start = self.current
        now = self.clock()
        self.trace.add(now, trajectory.sample(now - start), self.station.joints_rad())

    def wait(self, predicate, timeout_s: float) -> bool:
        def watched() -> bool:
            self._sample()
            return predicate()

        return self.station.wait_in_job(self.ctx, watched, timeout_s)

    def command(self, trajectory) -> float:
        self.station.start_trajectory(self.ctx, trajectory)
        start = self.clock()
        self.current = (trajectory, start)
        return start

    def report(self) -> None:
        plan, now = self.plan, self.clock()
        left = None
        if self.cycles is not None and self.phase != "ease in":
            end = self.anchor_s + (self.cycles - 1) * plan.cycle_s + plan.last_cycle_s
            left = max(0.0, end - now)
        last = np.diff(self.cycle_starts_s[-6:]).round(6).tolist()
        self.ctx.job.update_extra(repeat={
            "program_id": self.program.id,
            "cycle": min(self.cycle + 1, self.cycles or self.cycle + 1),
            "cycles": self.cycles,
            "waypoint": self.waypoint + 1,
            "waypoints": len(self.program.waypoints),
            "phase": "paused" if self.control.paused else self.phase,
            "paused": self.control.paused,
            "speed_percent": self.control.speed_percent,
            "cycle_s": plan.cycle_s,
            "time_left_s": left,
            "last_cycle_times_s": last,
            "blended_runs": plan.blended_runs,
            "runs": plan.runs,
        })
        total = self.cycles or 0
        fraction = (self.cycle + min(1.0, max(0.0, (now - self.anchor_s - self.cycle * plan.cycle_s) / plan.cycle_s))) / total if total else 0.0
        cycles_text = f"{self.cycles}" if self.cycles is not None else "∞"
        cycle = min(self.cycle + 1, self.cycles or self.cycle + 1)
        self.ctx.progress(min(fraction, 1.0),
                          f"cycle {cycle}/{cycles_text}, waypoint {self.waypoint + 1}/{len(self.program.waypoints)}")

    # Moves with pause, step and speed changes -------------------------------------------------------

    def _wait_paused(self, planner=None) -> str:
        """Hold still until resumed ("resume") or asked to step ("step"). planner() -> (Run or None, name): the step
        this wait is at, planned as it will run, offered meanwhile for a plan shown before it runs (plan_job_step)."""
        self.phase_before, self.phase = self.phase, "paused"
        self.control.offer_step(planner)
        try:
            self.report()
            while True:
                if self.control.take_step():
                    return "step"
                if not self.control.paused:
                    return "resume"
                version = self.control.version
                self.wait(lambda: self.control.version != version, WAIT_LIMIT_S)
        finally:
            self.control.offer_step(None)

    def _step_run(self, points: list, target: int, labels: list[int]) -> Run:
        """The run a single step makes from where the arm holds to points[target] alone (no blend) at the speed now."""
        here = self.station.start_position()
        return checked_run(self.station, np.vstack([here, points[target]]), [-1, labels[target]],
                           self._limits(self._speed()), None, self.settings, allow_blend=False)

    def _move_planner(self, points: list, remaining: list[int], labels: list[int]):
        """The planner a pause inside a move offers: its next step, to points[remaining[0]] (the lists are not mutated:
        move() makes new ones, so a request thread may call it while the job waits)."""

        def plan():
            label = labels[remaining[0]]
            name = "move home" if label == HOME_LABEL else f"move to waypoint {label + 1}"
            return self._step_run(points, remaining[0], labels), name

        return plan

    def _brake(self) -> None:
        """Pause: brake the motion in progress to rest on a jerk-limited stop within the limits of the speed it
        runs at (or the arm's own, when that stop fails the motion check); if neither passes, the run goes on
        to its end and the pause holds there."""
        for speed in (max(self.run_speed, self.control.speed_percent), 100.0):
            limits = self._limits(speed)

            def stop(handover):
                if handover is None:
                    raise PlanRefused("the run has ended")
                return plan_stop(handover.position_rad, handover.velocity_rad_s, handover.accel_rad_s2, limits, self.settings.rate_hz)

            try:
                trajectory, t0, _ = self.station.replace_trajectory(self.ctx, stop)
            except (*PLAN_REFUSALS, CommandRefused):
                continue
            self.current = (trajectory, t0)
            break
        self.wait(lambda: not self.station.arm.is_moving(), 30.0)

    def _limits(self, speed_percent: float):
        return station_limits(self.station, self.settings).scaled(speed_percent / 100.0)

    def _speed(self) -> float:
        """The speed the next motion runs at: the override, capped during the ease-in and the way home."""
        return min(self.control.speed_percent, self.speed_cap)

    def _replan(self, points: list, targets: list[int]):
        """A speed change: the rest of the run from the motion in progress (the handover: position, velocity,
        acceleration) at the new speed, sent through the gate. Velocity is limited at the new speed; acceleration
        and jerk at the faster of the old and new, so slowing down brakes as hard as the run it replaces would
        (time-scaled limits at 10 % allow 1 % of the acceleration and carried the arm past its joint limits).
        Returns (run, its start on the clock) or None when it cannot be planned or fails the motion check: the
        running plan goes on, the new speed applies from the next stop (the event log says why)."""
        speed = self._speed()
        fast = self._limits(max(speed, self.run_speed))
        slow = self._limits(speed)
        limits = Limits(slow.velocity_rad_s, fast.accel_rad_s2, fast.jerk_rad_s3)
        planned: dict = {}

        def plan(handover):
            if handover is None:
                raise PlanRefused("the run has ended")
            run = plan_run(np.vstack([handover.position_rad, [points[i] for i in targets]]), limits,
                           start_velocity=handover.velocity_rad_s, start_accel=handover.accel_rad_s2,
                           tick_s=tick_s(self.station), rate_hz=self.settings.rate_hz)
            planned["run"] = run
            return run.trajectory

        try:
            trajectory, t0, run_start = self.station.replace_trajectory(self.ctx, plan)
        except (*PLAN_REFUSALS, CommandRefused) as error:
            self.station.events.add("warn", f"repeat: speed {speed:g} % applies from the next stop ({error})")
            return None
        self.current = (trajectory, t0)
        self.run_speed = speed
        return planned["run"], run_start

    def move(self, points: list, run: Run, labels: list[int], speed_cap: float = 100.0) -> None:
        """Execute a run through points (the first is where the arm is), reacting to the RunControl.
        speed_cap: the fastest speed (%) of this move's runs (the ease-in and the way home)."""
        self.speed_cap = speed_cap
        self.run_speed = self._speed()
        remaining = list(range(1, len(points)))
        pending, started = run, None
        while True:
            if self.control.paused or self.control.steps_pending or pending is None:  # None: braked, resumed since
                action = "resume"
                if self.control.paused or self.control.steps_pending:
                    action = self._wait_paused(self._move_planner(points, remaining, labels))
                    self.phase = self.phase_before
                here = self.station.start_position()
                targets = remaining[:1] if action == "step" else remaining
                self.run_speed = self._speed()
                planned = self.control.take_planned() if action == "step" else None  # a step's plan shown, executed
                if planned is not None:
                    pending, started = planned, None
                elif action == "step":
                    pending, started = self._step_run(points, targets[0], labels), None
                else:
                    pending, started = checked_run(self.station, np.vstack([here, [points[i] for i in targets]]),
                                                   [-1, *(labels[i] for i in targets)], self._limits(self.run_speed),
                                                   None, self.settings), None
                if action == "step":
                    self._run_to_end(pending, targets, labels)
                    remaining = remaining[1:]
                    if not remaining:
                        return
                    continue
            outcome = self._run_to_end(pending, remaining, labels, started)
            if outcome is None:
                return
            start, passed = outcome
            if self.control.paused:
                remaining = remaining[passed:]
                self._brake()
                pending, started = None, None
                continue
            self.speed_seen = self.control.speed_percent
            replanned = self._replan(points, remaining[passed:])
            if replanned is None:  # refused: the running plan goes on to its end
                started = start
                continue
            remaining = remaining[passed:]
            pending, started = replanned

    def _run_to_end(self, run: Run, remaining: list[int], labels: list[int], started: float | None = None):
        """Command `run` (unless it was sent already and started at `started`) and wait for its end (None) or a
        control change ((its start, waypoints passed))."""
        version = self.control.version
        start = self.command(run.trajectory) if started is None else started
        self.report()
        done = self.wait(lambda: self.clock() >= start + run.duration_s - self.eps or self.control.version != version,
                         max(0.0, start + run.duration_s - self.clock()) + 5.0)
        elapsed = self.clock() - start
        finished = elapsed >= run.duration_s - self.eps or not done
        passed = len(remaining) if finished else sum(1 for t in run.arrival_s[1:] if t <= elapsed + self.eps)
        if passed and 0 <= labels[remaining[passed - 1]] < len(self.program.waypoints):
            self.waypoint = labels[remaining[passed - 1]]
        return None if finished else (start, passed)

    # Steps --------------------------------------------------------------------------------------------

    def deadline(self, step: Step) -> float:
        return self.anchor_s + self.cycle * self.plan.cycle_s + step.offset_s

    def reanchor(self, step: Step, end_s: float) -> None:
        """After a disruption: the next step's deadline is `end_s` (the end of this one as it happened)."""
        self.anchor_s = end_s - (self.cycle * self.plan.cycle_s + step.offset_s + step.duration_s)

    def do_step(self, step: Step) -> None:
        waypoints = self.program.waypoints
        self.wait(lambda: self.clock() >= self.deadline(step) - self.eps, max(0.0, self.deadline(step) - self.clock()) + 5.0)
        disrupted = self.control.version
        if step.kind != "move" and (self.control.paused or self.control.steps_pending):
            name = f"{step.action or step.kind} at waypoint {step.waypoint + 1}"
            self._wait_paused(lambda: (None, name))  # a step request is used up by this gripper step or dwell
            self.phase = self.phase_before
        if step.kind == "move":
            points = [waypoints[i].joints_rad for i in step.points]
            self.move(points, step.run, list(step.points))
        elif step.kind == "gripper":
            self.wait(lambda: not self.station.arm.is_moving(), 5.0)
            self.station.run_gripper(self.ctx, step.action)
            self.waypoint = step.waypoint
        if self.control.version != disrupted or self.control.speed_percent != self.plan.speed_percent:
            self.plan = self._plan(self.control.speed_percent)  # the new speed's plan, anchored where we are
            self.reanchor(self._same_step(step), self.clock())
            return
        end = self.deadline(step) + step.duration_s
        self.wait(lambda: self.clock() >= end - self.eps, max(0.0, end - self.clock()) + 5.0)

    def _same_step(self, step: Step) -> Step:
        return self.plan.steps[self._index]

    def run(self) -> dict:
        station, waypoints = self.station, self.program.waypoints
        first = np.asarray(waypoints[0].joints_rad)
        points, ease, labels = self.ease_in or plan_ease_in(station, station.start_position(), first,
                                                            self.control.speed_percent, self.settings)
        ease_cap = 100.0 * self.settings.ease_in_speed_fraction
        self.move(points, ease, labels, ease_cap)
        self.wait(lambda: not station.arm.is_moving(), 5.0)
        if station.gripper.read_state().command != waypoints[0].gripper:
            station.run_gripper(self.ctx, waypoints[0].gripper)
        self.phase, self.anchor_s = "cycle", self.clock()
        while self.cycles is None or self.cycle < self.cycles:
            if self.control.speed_percent != self.plan.speed_percent:
                self.plan = self._plan(self.control.speed_percent)
                self.anchor_s = self.clock() - self.cycle * self.plan.cycle_s
            self.cycle_starts_s.append(self.clock())
            self.trace.start_cycle(self.cycle + 1)
            self.report()
            last = self.cycles is not None and self.cycle == self.cycles - 1
            self._index = 0
            while self._index < len(self.plan.steps):
                step = self.plan.steps[self._index]
                if not (last and step.closing):
                    self.do_step(step)
                self._index += 1
            station.events.add("info", f"repeat: cycle {self.cycle + 1} done")
            self.cycle += 1
        self.trace.start_cycle(self.cycle + 1)
        self.phase = "home"
        here = station.start_position()
        home = plan_transfer(station, here, station.model.home_rad, self.control.speed_percent, self.settings,
                             labels=(len(waypoints) - 1, HOME_LABEL))
        self.move([here, np.asarray(station.model.home_rad)], home, [len(waypoints) - 1, HOME_LABEL], ease_cap)
        self.wait(lambda: not station.arm.is_moving(), 5.0)
        self.report()
        return {
            "program_id": self.program.id,
            "cycles_done": self.cycle,
            "cycle_s": self.plan.cycle_s,
            "cycle_starts_s": self.cycle_starts_s,
            "speed_percent": self.control.speed_percent,
        }


def repeat(station: Station, program_id: int, cycles: int | None = 1, speed_percent: float | None = None,
           source: str | None = None, settings: RepeatSettings = RepeatSettings(), plan_only: bool = False) -> Job | dict:
    """Start repeating program `program_id` `cycles` times (None: until cancelled) at `speed_percent`: the station's
    speed override (None: as it is; a number becomes the override once the job has started, station/job_control.py set_speed).

    Refused before anything moves (ValueError, UnsafeTrajectory, NotFound, CommandRefused) when the state
    does not allow it, the numbers are out of range, or a waypoint or segment fails the motion check.
    plan_only: the same planning and refusals, nothing moves; the plan (the ease-in, one cycle, the way home) is kept
    and Execute starts the repeat on exactly those motions (Station.plan_job)."""
    if plan_only:
        return station.plan_job("repeat", lambda: _planned(station, program_id, cycles, speed_percent, source, settings),
                                source=source)
    return _start(station, _checked(station, program_id, cycles, speed_percent, source, settings), source, settings)


@dataclass(frozen=True)
class _Checked:
    """A repeat's request checked and planned, before its job starts. ease_in: (points, run, labels) from the
    measured joints; exact: it was handed in (a plan shown, then executed) and the job runs it as it is."""

    program: object
    cycles: int | None
    speed_percent: float
    plans: dict  # cycle plans by speed, shared with the speed check of set_job_speed
    ease_in: tuple
    home: Run
    exact: bool


def _checked(station: Station, program_id: int, cycles: int | None, speed_percent: float | None, source: str | None,
             settings: RepeatSettings, ease_in: tuple | None = None, plans: dict | None = None) -> _Checked:
    """repeat()'s refusals (state, numbers, the program, every waypoint and segment) and its plans. ease_in, plans:
    planned already (the plan Execute runs), used as they are."""
    station.allowed_or_raise("repeat", source)
    if cycles is not None and (isinstance(cycles, bool) or not isinstance(cycles, int) or not 1 <= cycles <= MAX_CYCLES):
        raise InvalidInput(f"cycles must be an integer from 1 to {MAX_CYCLES} (or none: until stopped), got {cycles!r}")
    speed_percent = checked_speed_percent(station.speed_percent if speed_percent is None else speed_percent)
    program = station.store.get_program(program_id, station.program_owner)  # another arm's program: WrongArm
    plans = dict(plans or {})
    plans[speed_percent] = plans.get(speed_percent) or plan_cycle(station, program, speed_percent, settings)
    exact = ease_in is not None
    if not exact:
        ease_in = plan_ease_in(station, station.joints_rad(), program.waypoints[0].joints_rad, speed_percent, settings)
    home = plan_transfer(station, program.waypoints[-1].joints_rad, station.model.home_rad, speed_percent, settings,
                         labels=(len(program.waypoints) - 1, HOME_LABEL))
    return _Checked(program, cycles, speed_percent, plans, ease_in, home, exact)


def _start(station: Station, checked: _Checked, source: str | None, settings: RepeatSettings) -> Job:
    """The repeat's job started on the checked plans (the ease-in planned again when the job starts unless exact)."""
    program, cycles, speed_percent, plans = checked.program, checked.cycles, checked.speed_percent, checked.plans
    control = RunControl(speed_percent)
    control.trace = CycleTrace(station.model.joint_names)

    def check_speed(speed: float) -> None:  # a speed the cycle cannot be planned at is refused, the job runs on
        if speed not in plans:
            plans[speed] = plan_cycle(station, program, speed, settings)

    control.validate_speed = check_speed
    ease_in = checked.ease_in if checked.exact else None

    def run(ctx: JobContext) -> dict:
        return _Runner(station, ctx, program, cycles, control, settings, control.trace, plans, ease_in).run()

    times = f"× {cycles}" if cycles is not None else "until stopped"
    job = station.start_job("repeat", "repeat", run, detail=f"program '{program.name}' {times} at {speed_percent:g} %",
                            source=source, control=control)
    station.set_speed(speed_percent, source=source)  # the one override: the top bar shows the repeat's speed
    return job


def _planned(station: Station, program_id: int, cycles: int | None, speed_percent: float | None, source: str | None,
             settings: RepeatSettings) -> tuple[list, list[str], object]:
    """Station.plan_job's make(): the repeat's motions as the job will send them, their names, and its start."""
    checked = _checked(station, program_id, cycles, speed_percent, source, settings)
    plan = checked.plans[checked.speed_percent]
    trajectories, names = [checked.ease_in[1].trajectory], ["ease in to waypoint 1"]
    for step in plan.steps:
        if cycles == 1 and step.closing:
            continue  # a single cycle does not return to waypoint 1
        if step.kind == "move":
            trajectories.append(step.run.trajectory)
            names.append(f"move to waypoint {step.waypoint + 1}")
        else:
            names.append(f"{step.action or step.kind} at waypoint {step.waypoint + 1}")
    trajectories.append(checked.home.trajectory)
    names.append("home")
    times = "once" if cycles == 1 else (f"× {cycles} (one cycle shown)" if cycles else "until stopped (one cycle shown)")
    names[0] = f"{names[0]} ({len(checked.program.waypoints)} waypoints, {times})"

    def start() -> Job:  # checked again when executed (state, program), on exactly the motions shown
        again = _checked(station, program_id, cycles, speed_percent, source, settings, ease_in=checked.ease_in,
                         plans={plan.speed_percent: plan})
        return _start(station, again, source, settings)

    return trajectories, names, start


__all__ = ["CycleTrace", "repeat"]
