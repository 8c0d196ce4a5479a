"""Controls of a running job beyond cancel: pause, resume, step, speed override (the repeat job has them).

`JobControls` is a mixin of core.Station: each control is an operator command of the transition table
(allowed only in `repeat`, from the controller holding the lease), forwarded to the job's `RunControl`.
`RunControl` is the thread-safe mailbox between the request threads and the job's thread: the job
reads it at its waits and reacts (brake to rest on pause, re-plan on a speed change).
"""

from __future__ import annotations

import threading

from armlab.errors import CommandRefused, InvalidInput

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
            self._paused, self._steps = False, 0
            self._bump()

    def step(self) -> None:
        """While paused: go on to the next waypoint (and do what it says), then pause again. Running: pause there."""
        with self._lock:
            self._steps += 1
            self._paused = True
            self._bump()

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


class JobControls:
    """pause_job, resume_job, step_job, set_job_speed: table-checked, forwarded to the job's RunControl."""

    def _run_control(self, command: str, source: str | None) -> RunControl:
        with self._lock:
            self._check(command, source)
            job = self._job
            control = getattr(job, "control", None)
            if not isinstance(control, RunControl):
                state = self._effective_state().value
                raise CommandRefused(command, f"{state} (the job '{getattr(job, 'name', '')}' has no {command})", ["cancel", "estop"])
            self._transition(command, source=source)  # repeat stays repeat; a free lease goes to `source`
        return control

    def pause_job(self, source: str | None = None):
        self._run_control("pause", source).pause()
        self.events.add("info", "job paused")
        return self.current_job()

    def resume_job(self, source: str | None = None):
        self._run_control("resume", source).resume()
        self.events.add("info", "job resumed")
        return self.current_job()

    def step_job(self, source: str | None = None):
        self._run_control("step", source).step()
        return self.current_job()

    def set_job_speed(self, speed_percent: float, source: str | None = None):
        """The running repeat's speed: the station's one speed override (speed.py set_speed), refused (CommandRefused)
        when no job with controls runs."""
        speed = checked_speed_percent(speed_percent)
        self._run_control("set_speed", source)
        self.set_speed(speed, source=source)
        return self.current_job()
