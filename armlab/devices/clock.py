"""The clock motion is timed on, injected into the station: the wall clock for real devices, the simulation's own
clock when the devices are simulated (SimWorkcell.clock: its fast mode advances only while someone waits on it,
its real-time mode runs at its time scale). The station asks a Clock for the time and waits on it; it never reads
a simulator's time itself."""

from __future__ import annotations

import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable

POLL_S = 0.002  # how often WallClock.wait_for looks at its predicate


class Clock(ABC):
    """Time in seconds on one monotonic scale, and waiting on it."""

    @abstractmethod
    def now_s(self) -> float:
        """The clock's time (seconds; only differences mean anything)."""

    @abstractmethod
    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Block until predicate() holds or about timeout_s of this clock's time passed; returns predicate()."""


class WallClock(Clock):
    """The machine's monotonic clock: real devices move in real time."""

    def __init__(self, poll_s: float = POLL_S) -> None:
        self._poll_s = poll_s
        self._never = threading.Event()  # waited on between looks: a sleep that does not hold the GIL

    def now_s(self) -> float:
        return time.monotonic()

    def wait_for(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while not predicate():
            if time.monotonic() >= deadline:
                return predicate()
            self._never.wait(self._poll_s)
        return True
