"""The control lease: exactly one controller commands the station at a time (issue 10, item 3).

A controller is a name the server derives from the connection (the page's websocket session id, a
script's X-Armlab-Controller header). A free lease goes to the first controller that commands; from then
on, commands from anyone else are refused (NotController naming the holder) until the holder releases
it, its connection goes away, or someone takes it over with an explicit take(), which the event log
announces to every client, the previous holder included. E-stop never needs the lease. In-process
callers that name no controller (evaluations, tests: source=None) are not subject to it.
Not thread-safe on its own: the station calls it under its lock.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass

from armlab.errors import InvalidInput, NotController

CONTROLLER_NAME = re.compile(r"^[A-Za-z0-9_.:-]{1,64}$")


def checked_controller(name: str) -> str:
    """A controller name (1-64 of letters, digits, _ . : -), else ValueError."""
    if not isinstance(name, str) or not CONTROLLER_NAME.match(name):
        raise InvalidInput(f"controller name must be 1-64 letters, digits or _ . : -, got {name!r}")
    return name


@dataclass
class ControlLease:
    """Who controls the station (holder, None = free) and since when (time.time())."""

    holder: str | None = None
    since_s: float | None = None

    def require(self, source: str | None, command: str) -> bool:
        """NotController unless `source` may command now; a free lease is taken. True if it was taken."""
        if source is None or self.holder == source:
            return False
        if self.holder is not None:
            raise NotController(command, self.holder)
        self.holder, self.since_s = source, time.time()
        return True

    def take(self, source: str) -> str | None:
        """Take the lease over explicitly; returns the previous holder (None if it was free)."""
        previous = self.holder
        self.holder, self.since_s = checked_controller(source), time.time()
        return previous

    def release(self, source: str) -> bool:
        """Give the lease up if `source` holds it; True if it did."""
        if self.holder != source or source is None:
            return False
        self.holder, self.since_s = None, None
        return True

    def to_dict(self) -> dict:
        return {"controller": self.holder, "since_s": self.since_s}
