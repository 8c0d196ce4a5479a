"""Cancellable long actions (calibrate, grab, drop, repeat, autonomous tasks), one at a time.

A job runs its function in its own thread with a JobContext; the function reports progress and calls
`ctx.check()` between steps, which raises JobCancelled once cancel() was called. The station decides
what a job may do to the devices; this module only knows threads, progress and outcome.
"""

from __future__ import annotations

import logging
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from armlab.errors import is_internal

log = logging.getLogger(__name__)


class JobCancelled(Exception):
    """Raised inside a job's thread when the job was cancelled (or the station was e-stopped)."""


@dataclass
class JobContext:
    """What a running job sees: its cancel flag and a progress reporter."""

    job: Job
    in_cleanup: bool = False  # True while the job's cleanup runs after a cancel

    def check(self) -> None:
        """Raise JobCancelled if the job was cancelled."""
        if self.job.cancel_event.is_set():
            raise JobCancelled(f"job '{self.job.name}' was cancelled")

    def progress(self, fraction: float, message: str | None = None) -> None:
        """Report progress in [0, 1] with an optional human sentence; also a cancellation point."""
        self.check()
        self.job.update(progress=min(1.0, max(0.0, float(fraction))), message=message)

    def sleep(self, duration_s: float) -> None:
        """Sleep, waking at once (and raising JobCancelled) on cancel."""
        if self.job.cancel_event.wait(max(0.0, duration_s)):
            self.check()


@dataclass
class Job:
    """One long action. state: running | succeeded | failed | cancelled."""

    name: str
    detail: str = ""
    id: str = field(default_factory=lambda: uuid.uuid4().hex[:12])
    state: str = "running"
    progress: float = 0.0
    message: str = ""
    result: Any = None
    started_s: float = field(default_factory=time.time)
    finished_s: float | None = None
    has_cleanup: bool = False  # a cleanup runs after a cancel (the station waits for it)
    halted: bool = False  # cancelled by an e-stop or a device loss: no cleanup, the gripper keeps what it holds
    extra: dict = field(default_factory=dict)  # job-specific live details (e.g. a task's progress)
    control: Any = field(default=None, repr=False)  # pause/resume/step/speed mailbox (job_control.RunControl) if the job has one
    cancel_event: threading.Event = field(default_factory=threading.Event, repr=False)
    thread: threading.Thread | None = field(default=None, repr=False)  # the job's thread (joined at shutdown)
    done_event: threading.Event = field(default_factory=threading.Event, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def update(self, progress: float | None = None, message: str | None = None) -> None:
        with self._lock:
            if progress is not None:
                self.progress = progress
            if message is not None:
                self.message = message

    def update_extra(self, **values: Any) -> None:
        """Merge job-specific live details into `extra` (shown in GET /api/jobs/current)."""
        with self._lock:
            self.extra = {**self.extra, **values}

    def finish(self, state: str, message: str, result: Any = None) -> None:
        with self._lock:
            self.state = state
            self.message = message
            self.result = result
            self.finished_s = time.time()
            if state == "succeeded":
                self.progress = 1.0

    def cancel(self, halted: bool = False) -> None:
        """Cancel; halted: by an e-stop or a device loss (the arm is halted and latched: no cleanup runs)."""
        if halted:
            self.halted = True
        self.cancel_event.set()

    @property
    def done(self) -> bool:
        return self.done_event.is_set()

    def wait(self, timeout_s: float | None = None) -> bool:
        """Block until the job ends; False on timeout."""
        return self.done_event.wait(timeout_s)

    def to_dict(self) -> dict:
        with self._lock:
            return {
                "id": self.id,
                "name": self.name,
                "detail": self.detail,
                "state": self.state,
                "progress": round(self.progress, 4),
                "message": self.message,
                "started_s": self.started_s,
                "finished_s": self.finished_s,
                "result": jsonable(self.result),
                **({"extra": jsonable(self.extra)} if self.extra else {}),
            }


def jsonable(value: Any) -> Any:
    """numpy arrays and scalars (also nested in dicts, lists, tuples) → plain JSON-ready Python values."""
    if isinstance(value, dict):
        return {str(key): jsonable(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(item) for item in value]
    if hasattr(value, "tolist"):  # numpy arrays and numpy scalars
        return value.tolist()
    return value


def start_job_thread(
    job: Job,
    function: Callable[[JobContext], Any],
    on_end: Callable[[Job, BaseException | None], None],
    cleanup: Callable[[JobContext], Any] | None = None,
) -> threading.Thread:
    """Run `function(ctx)` in a daemon thread; finish the job by its outcome, call on_end(job, error), then mark it done.

    Outcomes: returned → succeeded (its return value is the result); JobCancelled → cancelled;
    any other exception → failed with the exception's sentence (passed to on_end so the station can
    tell device failures from refusals); a bug (armlab.errors.is_internal) → failed as "internal error: ...",
    its traceback logged at ERROR. After a cancel, cleanup(ctx) runs (its failure is reported in
    the job's message), except after an e-stop or a device loss (job.halted): the arm stays halted.
    """

    def run() -> None:
        error: BaseException | None = None
        try:
            result = function(JobContext(job))
        except JobCancelled as cancelled:
            message = str(cancelled) or "cancelled"
            if job.halted:  # e-stop or device loss: nothing moves until reset; a held block stays held
                message += "; halted where it was (e-stop or a lost device): the gripper keeps what it holds"
            elif cleanup is not None:
                try:
                    outcome = cleanup(JobContext(job, in_cleanup=True))
                    message += f"; {outcome}" if outcome else ""
                except Exception as failure:  # noqa: BLE001 - reported, the job is cancelled either way
                    message += f"; cleanup failed: {type(failure).__name__}: {failure}"
            job.finish("cancelled", message)
        except Exception as failure:  # noqa: BLE001 - a job's failure is reported, never raised into the void
            error = failure
            if is_internal(failure):  # a bug (a bare ValueError from numpy...), not a refusal: say so, keep the traceback
                log.error("job %s failed on an internal error", job.name, exc_info=True)
                job.finish("failed", f"internal error: {type(failure).__name__}: {failure} (the server log has the traceback)")
            else:
                log.info("job %s failed", job.name, exc_info=True)
                job.finish("failed", f"{type(failure).__name__}: {failure}")
        else:
            job.finish("succeeded", job.message or "done", result)
        try:
            on_end(job, error)
        finally:
            job.done_event.set()  # after the station's transition, so a waiter sees the final state

    thread = threading.Thread(target=run, name=f"job-{job.name}", daemon=True)
    job.thread = thread
    thread.start()
    return thread
