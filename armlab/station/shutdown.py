"""Stopping the station's threads at close: the job's, the workers' (camera, perception, telemetry, device watch)
and the event history's writer, each join bounded by one shared deadline, and a report of what ended."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

log = logging.getLogger(__name__)


def stop_threads(job_thread: threading.Thread | None, workers: Sequence[Any], close_history: Callable[[], bool],
                 timeout_s: float) -> dict:
    """Join the job's thread, stop the workers (all asked first, then joined newest first) and close the event
    history, all within timeout_s; returns {"joined": [thread names], "alive": [names still running]} and logs it."""
    deadline = time.monotonic() + timeout_s
    joined, alive = [], []
    if job_thread is not None:
        job_thread.join(max(0.0, deadline - time.monotonic()))
        (alive if job_thread.is_alive() else joined).append(job_thread.name)
    for worker in workers:
        worker.request_stop()
    for worker in reversed(workers):
        ended = worker.stop(max(0.05, deadline - time.monotonic()))
        (joined if ended else alive).append(worker.name)
    (joined if close_history() else alive).append("event-history")
    if alive:
        log.warning("station closed; threads still running: %s (joined: %s)", ", ".join(alive), ", ".join(joined) or "none")
    else:
        log.info("station closed; threads joined: %s", ", ".join(joined) or "none")
    return {"joined": joined, "alive": alive}
