"""The station's job commands: start a job, cancel it, and the controls beyond cancel: pause, resume, step,
speed (the repeat job has them); and the station's speed override (set_speed).

`JobControls` is a command object core.Station owns (station.job_commands; the station forwards its public methods);
the job slots and the state it changes are the station's (core.py). start_job enters the job's state and runs it on its own thread
(jobs.py); its end returns the station to idle and records it. Each control is an operator command of the
transition table (allowed only in `repeat`, from the controller holding the lease), forwarded to the job's `RunControl`.
`RunControl` is the thread-safe mailbox between the request threads and the job's thread: the job
reads it at its waits and reacts (brake to rest on pause, re-plan on a speed change).

The speed override: one percentage (10-100 %) for every motion the station plans, jobs, manual moves and repeats
alike, shown in the status (`speed_percent`). The gate holds it and paces each motion as it sends it (motion.py:
planned at full speed, time-scaled along the same path by armlab.motion.time_warp). A repeat plans its own runs at
the override (its RunControl holds the same number: a change goes to it, and it re-plans the rest of its run,
skills/repeat.py). Any other motion running when the override changes has its remainder re-timed from a handover of
the running command (checked like every motion); when that cannot be sent, the motion runs on at its speed and the
new one applies from the next motion (the event log says so). Jogs keep their own speed (the operator's velocity).
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PLAN_REFUSALS, ArmMoving, CommandRefused, InvalidInput, PlanStale
from armlab.motion.handover import Handover
from armlab.motion.planning_limits import planning_accel_rad_s2
from armlab.motion.time_warp import retimed
from armlab.station.jobs import Job, JobContext, start_job_thread
from armlab.station.perception import DEVICE_ERRORS
from armlab.station.states import JOB_STATES

log = logging.getLogger(__name__)

SPEED_MIN_PERCENT = 10.0
SPEED_MAX_PERCENT = 100.0


SPEED_WAIT_FACTOR = SPEED_MAX_PERCENT / SPEED_MIN_PERCENT  # a paced motion takes at most this many times its full-speed duration


def checked_speed_percent(speed_percent: float) -> float:
    """A speed override: a finite number in [10, 100] %, else InvalidInput (a ValueError)."""
    try:
        value = float(speed_percent)
    except (TypeError, ValueError):
        raise InvalidInput(f"speed_percent must be a number from {SPEED_MIN_PERCENT:g} to {SPEED_MAX_PERCENT:g} %, got {speed_percent!r}") from None
    if not SPEED_MIN_PERCENT <= value <= SPEED_MAX_PERCENT:
        raise InvalidInput(f"speed_percent must be from {SPEED_MIN_PERCENT:g} to {SPEED_MAX_PERCENT:g} %, got {speed_percent!r}")
    return value


class RunControl:
    """Pause / resume / step / speed of one running job; `version` grows with every change so the job's
    waits notice it (they poll `version`, never block on it)."""

    def __init__(self, speed_percent: float = 100.0) -> None:
        self._lock = threading.Lock()
        self._speed_percent = checked_speed_percent(speed_percent)
        self._paused = False
        self._steps = 0
        self._offer = None  # while the job waits paused at a step: what that step would run (plan_next_step)
        self._offers = 0  # how many steps the job has offered so far
        self._planned = None  # what a planned step handed in for the job to run (its Run; None: plan it then)
        self.version = 0
        self.trace = None  # the job's record of commanded and measured joints (repeat: skills.repeat.CycleTrace)
        self.validate_speed = None  # the job's check of a new speed (raises with the reason), run before it applies

    def _bump(self) -> None:
        self.version += 1

    def pause(self) -> None:
        with self._lock:
            self._paused = True
            self._bump()

    def resume(self) -> None:
        with self._lock:
            self._paused, self._steps, self._planned = False, 0, None
            self._bump()

    def step(self) -> None:
        """While paused: go on to the next waypoint (and do what it says), then pause again. Running: pause there."""
        with self._lock:
            self._take_step(None)

    def _take_step(self, planned) -> None:
        """One more step to go, then pause; planned: the Run the step runs (None: the job plans it). Under the lock."""
        self._steps += 1
        self._paused = True
        self._planned = planned
        self._bump()

    # The next step, planned without moving (issue 22: single-stepping with plan, then execute) ----------------------

    def offer_step(self, planner: Callable[[], tuple] | None) -> None:
        """The job: it waits paused at a step; planner() -> (the step's Run or None for a gripper step or dwell, its
        name) plans that step as the job will run it. None: the job goes on (the offer is withdrawn)."""
        with self._lock:
            self._offer = planner
            if planner is not None:
                self._offers += 1

    @property
    def offers(self) -> int:
        with self._lock:
            return self._offers

    def step_offer(self) -> tuple[Callable[[], tuple], int]:
        """(the planner of the step the paused job waits at, the control's version then); CommandRefused when the job
        is not waiting at a step."""
        with self._lock:
            if self._offer is None or self._steps:
                raise CommandRefused("step", "repeat (the job is not waiting paused at a step: pause it, wait until it "
                                     "has stopped, then plan its next step)", ["pause", "step", "resume", "cancel"])
            return self._offer, self.version

    def step_planned(self, run, version: int) -> int:
        """Execute a planned step: the job runs exactly `run` (None: the gripper step or dwell it waits at) as its next
        step, then pauses again; PlanStale 'job_changed' when the job went on, was resumed, re-speeded or ended since
        the plan (its version differs, or it no longer waits at a step). Returns the offers count before the step."""
        with self._lock:
            if self._offer is None or self._steps or version != self.version:
                raise PlanStale("the plan is stale: the job went on (stepped, resumed, changed speed or ended) since the "
                                "plan was made; plan its next step again", "job_changed")
            self._take_step(run)
            return self._offers

    def take_planned(self):
        """The job, taking a step: the Run a planned step handed in (once), else None (plan the step now)."""
        with self._lock:
            planned, self._planned = self._planned, None
            return planned

    def set_speed(self, speed_percent: float) -> None:
        """Change the speed; InvalidInput (the job's reason, e.g. a waypoint the cycle fails at that speed) leaves it."""
        value = checked_speed_percent(speed_percent)
        if self.validate_speed is not None:
            try:
                self.validate_speed(value)
            except ValueError as error:
                raise InvalidInput(f"speed {value:g} % refused, the job goes on at {self.speed_percent:g} %: {error}") from None
        with self._lock:
            self._speed_percent = value
            self._bump()

    def take_step(self) -> bool:
        """The job: consume one step request (True) if there is one."""
        with self._lock:
            if self._steps > 0:
                self._steps -= 1
                return True
            return False

    @property
    def paused(self) -> bool:
        with self._lock:
            return self._paused

    @property
    def steps_pending(self) -> int:
        with self._lock:
            return self._steps

    @property
    def speed_percent(self) -> float:
        with self._lock:
            return self._speed_percent


@dataclass(frozen=True)
class StepTaken:
    """A planned step handed to the paused job (execute_plan's answer for a step plan): done() once the job waits at
    its next step again or has ended."""

    job: Any
    control: RunControl
    offers: int

    def done(self) -> bool:
        return bool(self.job.done) or self.control.offers > self.offers


class JobControls:
    """start_job, cancel_job, current_job; pause_job, resume_job, step_job, set_job_speed: table-checked, the
    controls forwarded to the job's RunControl; set_speed, the station's override. station: the core.Station."""

    def __init__(self, station) -> None:
        self._station = station

    def set_speed(self, speed_percent, source: str | None = None) -> float:
        """Set the override (InvalidInput outside 10-100 % or not a finite number: nothing changes). A running repeat
        takes it (its own check may refuse it: InvalidInput, nothing changes); any other motion in progress is re-timed
        from now on. Returns the override now in force."""
        speed = checked_speed_percent(speed_percent)
        station, gate = self._station, self._station.gate
        station.require_control("set_speed", source)
        refused = None
        with gate.speed_change():
            job = self.current_job()
            control = getattr(job, "control", None) if job is not None and not job.done else None
            if isinstance(control, RunControl) and control.speed_percent != speed:
                control.set_speed(speed)  # InvalidInput: the repeat's reason, nothing changes
            old = gate.set_speed_percent(speed)
            if not isinstance(control, RunControl) and speed != old:
                refused = self._retime_running(speed)
        if refused is not None:
            station.events.add("warn", f"speed {speed:g} % applies from the next motion: the one in progress runs on ({refused})")
        if speed != old:
            station.events.add("info", f"speed override set to {speed:g} %")
        return speed

    def _retime_running(self, speed: float) -> str | None:
        """Re-time the remainder of the motion in progress to `speed` (when it is one the override paced) through the
        gate; the reason when that could not be sent (the motion runs on at its speed), else None."""
        station, gate = self._station, self._station.gate
        with station._lock:
            running, paced_motion = gate.commanded, gate.paced_motion
        if running is None or paced_motion is None or running[0] is not paced_motion[0] or paced_motion[1] == speed:
            return None
        if gate.clock_s() - running[1] >= running[0].duration_s:
            return None  # it has ended
        ratio = speed / paced_motion[1]

        def plan(handover: Handover | None) -> JointTrajectory:
            current = gate.commanded
            if handover is None or current is None or current[2] != handover.source_id:
                raise InvalidInput("the motion ended or was replaced meanwhile")
            trajectory, t0 = current[0], current[1]
            return retimed(trajectory, handover.takes_over_s - t0, 1.0, ratio, planning_accel_rad_s2(station.model),
                           station.motion_config.sample_rate_hz)

        try:
            gate.send_replacing(plan, lambda: gate.pace_next_send(speed), "set_speed")
        except (*PLAN_REFUSALS, ArmMoving, CommandRefused) as error:
            return str(error)
        return None

    def _run_control(self, command: str, source: str | None, transition: bool = True) -> RunControl:
        """The running job's RunControl once `command` is allowed (CommandRefused: not allowed, or a job without
        controls); transition=False for a command that changes nothing (a plan)."""
        with self._station._lock:
            self._station._check(command, source)
            job = self._station._job
            control = getattr(job, "control", None)
            if not isinstance(control, RunControl):
                state = self._station._effective_state().value
                raise CommandRefused(command, f"{state} (the job '{getattr(job, 'name', '')}' has no {command})", ["cancel", "estop"])
            if transition:
                self._station._transition(command, source=source)  # repeat stays repeat; a free lease goes to `source`
        return control

    def pause_job(self, source: str | None = None):
        self._run_control("pause", source).pause()
        self._station.events.add("info", "job paused")
        return self.current_job()

    def resume_job(self, source: str | None = None):
        self._run_control("resume", source).resume()
        self._station.events.add("info", "job resumed")
        return self.current_job()

    def step_job(self, source: str | None = None):
        self._run_control("step", source).step()
        return self.current_job()

    def plan_job_step(self, source: str | None = None) -> dict:
        """The paused job's next step (the next waypoint's move, or the gripper step or dwell it waits at) planned as
        single-stepping runs it, kept as a plan and returned in its wire form; nothing moves. Execute hands the job
        exactly that motion (StepTaken); the plan goes stale once the arm or the scene changed, or the job went on."""
        control = self._run_control("step", source, transition=False)
        job = self.current_job()

        def make() -> tuple:
            planner, version = control.step_offer()
            run, name = planner()
            if run is None:  # a gripper step or a dwell: the arm stays where it is
                trajectory = JointTrajectory(np.zeros(1), np.asarray(self._station.start_position(), float)[None, :])
            else:
                trajectory = run.trajectory

            def start() -> StepTaken:
                return StepTaken(job, control, control.step_planned(run, version))

            return [trajectory], [name], start

        return self._station.plan_job("step", make, source)

    def set_job_speed(self, speed_percent: float, source: str | None = None):
        """The running repeat's speed: the station's one speed override (set_speed, above), refused (CommandRefused)
        when no job with controls runs."""
        speed = checked_speed_percent(speed_percent)
        self._run_control("set_speed", source)
        self.set_speed(speed, source=source)
        return self.current_job()

    # Start and cancel ------------------------------------------------------------------------------

    def cancel_job(self, source: str | None = None) -> Job:
        """Cancel the running job: the arm halts where it is, the station returns to idle.

        A job that registered a cleanup (e.g. put a held block down) runs it on its own thread after the
        cancel; the station stays in the job's state until that ends."""
        with self._station._lock:
            self._station._check("cancel", source)
            job = self._station._job
            assert job is not None, "a job state without a job"
            job.cancel()  # under the lock: any command the job is sending has finished or will see it
            if not job.has_cleanup:
                self._station._transition("cancel", source=source, detail="")
        self._station.latch.halt_devices(gripper=False)
        return job  # the job's end logs "job '<name>' cancelled: ..." once

    def current_job(self) -> Job | None:
        with self._station._lock:
            return self._station._job or self._station._last_job

    def start_job(
        self,
        command: str,
        name: str,
        function: Callable[[JobContext], Any],
        detail: str = "",
        source=None,
        cleanup: Callable[[JobContext], Any] | None = None,
        control: Any = None,
    ) -> Job:
        """Enter the job's state and run function(ctx) on a job thread (CommandRefused if not allowed).
        control: the job's RunControl (pause, resume, step, speed; job_control.py), if it has one.

        cleanup(ctx), if given, runs after a cancel (not after an e-stop) with the arm still the job's,
        e.g. to put a held block down; the station returns to idle when it ends."""
        with self._station._lock:
            self._station._check(command, source)
            if command not in ("calibrate", "grab", "drop", "repeat", "auto"):
                raise InvalidInput(f"'{command}' does not start a job")
            job = Job(name=name, detail=detail, has_cleanup=cleanup is not None, control=control)
            self._station._transition(command, source=source, detail=detail or name)
            self._station._job = job
            self._station._jog = None
            start_job_thread(job, self._after_rest(function), self._on_job_end, cleanup=cleanup)
        self._station.events.add("info", f"job '{name}' started" + (f": {detail}" if detail else ""))
        return job

    def _after_rest(self, function: Callable[[JobContext], Any]) -> Callable[[JobContext], Any]:
        """The job's function, run once a motion still in progress (a manual move, a jog running out) has been
        braked to rest (every job plans from the arm at rest) and the job's history row is written, by the job's
        own thread: a locked database delays the job, never the request that started it."""

        def run(ctx: JobContext) -> Any:
            self._station.brake_to_rest(ctx)
            try:  # on disk while it runs: a station killed mid-job shows it 'interrupted' after the restart
                self._station.store.record_job_start(ctx.job.to_dict())
            except Exception as store_error:  # noqa: BLE001 - the job matters more than its record
                log.warning("could not record the start of job %s: %s", ctx.job.id, store_error)
            return function(ctx)

        return run

    def _on_job_end(self, job: Job, error: BaseException | None) -> None:
        if isinstance(error, DEVICE_ERRORS) and self._station._job is job:
            self._station.device_failed(f"a device in job '{job.name}'", f"{type(error).__name__}: {error}")
        with self._station._lock:
            if self._station._job is job:
                self._station._job, self._station._last_job = None, job
                if self._station._state in JOB_STATES:
                    self._station._transition("job_ended", event=True)
        try:
            self._station.store.record_job(job.to_dict())
        except Exception as store_error:  # noqa: BLE001 - the job's outcome matters more than its record
            log.warning("could not record job %s: %s", job.id, store_error)
        level = {"succeeded": "info", "cancelled": "warn"}.get(job.state, "error")
        self._station.events.add(level, f"job '{job.name}' {job.state}: {job.message}")
