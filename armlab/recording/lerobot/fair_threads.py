"""Keep an encoder from putting the process's threads into real-time scheduling.

SVT-AV1 (the AV1 encoder LeRobot uses), run as root, puts the thread that feeds it and the ~40 worker threads it
starts into SCHED_FIFO at priority 99, and every thread those start later inherits it. On a station that is the
server's thread pool: a busy real-time thread starves the simulation, the camera and the e-stop path of its core
(the test suite's worker took the Playwright driver and Chromium it later started down with it). Linux schedules
per thread, so each thread's policy is read from /proc/self/task and put back."""

from __future__ import annotations

import os
from pathlib import Path

REALTIME_POLICIES = frozenset(getattr(os, name) for name in ("SCHED_FIFO", "SCHED_RR") if hasattr(os, name))


def thread_ids() -> list[int]:
    """The native ids of this process's threads (Linux; [] elsewhere)."""
    try:
        return [int(entry.name) for entry in Path("/proc/self/task").iterdir()]
    except (OSError, ValueError):
        return []


def realtime_thread_ids() -> set[int]:
    """This process's threads in a real-time policy (SCHED_FIFO or SCHED_RR)."""
    found = set()
    for tid in thread_ids():
        try:
            if os.sched_getscheduler(tid) in REALTIME_POLICIES:
                found.add(tid)
        except OSError:  # the thread ended meanwhile
            continue
    return found


class FairThreads:
    """`with FairThreads() as fair: ... fair.restore()`: threads that were not real-time when the block began are put
    back to SCHED_OTHER at every restore() and when the block ends (threads real-time before are left as they were)."""

    def __enter__(self) -> FairThreads:
        self._realtime_before = realtime_thread_ids()
        return self

    def restore(self) -> int:
        """Put threads made real-time since the block began back to SCHED_OTHER; returns how many."""
        restored = 0
        for tid in realtime_thread_ids() - self._realtime_before:
            try:
                os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))
                restored += 1
            except OSError:  # ended meanwhile
                continue
        return restored

    def __exit__(self, *exc) -> None:
        self.restore()
