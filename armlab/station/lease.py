"""The control lease: exactly one controller commands the station at a time (issue 10, item 3).

A controller is a name the server derives from the connection (the page's websocket session id, a
script's X-Armlab-Controller header). A free lease goes to the first controller that commands; from then
on, commands from anyone else are refused (NotController naming the holder) until the holder releases
it, its connection goes away, or someone takes it over with an explicit take(), which the event log
announces to every client, the previous holder included. E-stop never needs the lease. In-process
callers that name no controller (evaluations, tests: source=None) are not subject to it.
Owned by core.Station (station.lease), which asks it under its own lock whenever a command is checked; it keeps its
holder under a lock of its own and announces every change in the event log.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable
from typing import Any

from armlab.errors import InvalidInput, NotController, ShuttingDown

CONTROLLER_NAME = re.compile(r"^[A-Za-z0-9_.:-]{1,64}$")


def checked_controller(name: str) -> str:
    """A controller name (1-64 of letters, digits, _ . : -), else ValueError."""
    if not isinstance(name, str) or not CONTROLLER_NAME.match(name):
        raise InvalidInput(f"controller name must be 1-64 letters, digits or _ . : -, got {name!r}")
    return name


class ControlLease:
    """Who controls the station (holder, None = free) and since when (time.time()); events: the station's EventLog,
    told of every change; closing(): True while the station shuts down (no one takes the lease then)."""

    def __init__(self, events: Any, closing: Callable[[], bool] = lambda: False) -> None:
        self._events, self._closing = events, closing
        self._lock = threading.Lock()
        self._holder: str | None = None
        self._since_s: float | None = None

    @property
    def holder(self) -> str | None:
        with self._lock:
            return self._holder

    def check(self, source: str | None, command: str) -> None:
        """NotController (naming the holder) unless `source` may command now; the lease is not taken."""
        with self._lock:
            if source is not None and self._holder not in (None, source):
                raise NotController(command, self._holder)

    def require(self, source: str | None, command: str) -> bool:
        """NotController unless `source` may command now; a free lease is taken (and announced). True if it was taken."""
        with self._lock:
            if source is None or self._holder == source:
                return False
            if self._holder is not None:
                raise NotController(command, self._holder)
            self._holder, self._since_s = source, time.time()
        self._events.add("info", f"control taken by '{source}' (the lease was free)")
        return True

    def take(self, source: str) -> str | None:
        """Take the lease over explicitly (announced: the previous holder learns it); returns the previous holder (None
        if it was free). ShuttingDown while the station shuts down, InvalidInput for a bad name."""
        if self._closing():
            raise ShuttingDown("the station is shutting down")
        name = checked_controller(source)
        with self._lock:
            previous, self._holder, self._since_s = self._holder, name, time.time()
        if previous != source:
            taken_from = f" from '{previous}'" if previous else ""
            self._events.add("warn", f"control taken by '{source}'{taken_from}")
        return previous

    def release(self, source: str, reason: str = "released") -> bool:
        """Give the lease up if `source` holds it (announced with `reason`, e.g. 'disconnected'); True if it did."""
        with self._lock:
            if self._holder != source or source is None:
                return False
            self._holder, self._since_s = None, None
        self._events.add("info", f"control {reason}: '{source}' no longer controls the station")
        return True

    def to_dict(self) -> dict:
        with self._lock:
            return {"controller": self._holder, "since_s": self._since_s}
