"""Thread-safe "newest value wins" slots and a bounded event log.

A NewestSlot holds one value and a version number; writers replace the value, readers wait for a
version newer than the one they saw. Nothing queues, so a slow reader never grows memory.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any, Generic, TypeVar

from armlab.errors import InvalidInput

ValueT = TypeVar("ValueT")


class NewestSlot(Generic[ValueT]):
    """One value + version; `wait_newer(version)` blocks until a newer value is published."""

    def __init__(self) -> None:
        self._condition = threading.Condition()
        self._value: ValueT | None = None
        self._version = 0
        self._listeners: list[Callable[[ValueT, int], None]] = []

    def publish(self, value: ValueT) -> int:
        with self._condition:
            self._value = value
            self._version += 1
            version = self._version
            listeners = list(self._listeners)
            self._condition.notify_all()
        for listener in listeners:
            listener(value, version)
        return version

    def get(self) -> tuple[ValueT | None, int]:
        """The current value and its version (None, 0 before the first publish)."""
        with self._condition:
            return self._value, self._version

    def wait_newer(self, version: int, timeout_s: float) -> tuple[ValueT | None, int]:
        """Wait up to timeout_s for a version > `version`; returns the newest (value, version) either way."""
        deadline = time.monotonic() + timeout_s
        with self._condition:
            while self._version <= version:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    break
                self._condition.wait(remaining)
            return self._value, self._version

    def add_listener(self, listener: Callable[[ValueT, int], None]) -> None:
        """Call listener(value, version) from the publishing thread on every publish (keep it quick)."""
        with self._condition:
            self._listeners.append(listener)

    def remove_listener(self, listener: Callable[[ValueT, int], None]) -> None:
        with self._condition:
            if listener in self._listeners:
                self._listeners.remove(listener)


class EventLog:
    """The newest `capacity` operator events, each {"seq", "level", "kind", "message", "time_s"}. `kind` says what
    happened for a client to act on (the page keys on it, never on the message's text): "general" (for people
    only) or "scene" (the simulated scene was replaced)."""

    LEVELS = ("info", "warn", "error")
    KINDS = ("general", "scene")

    def __init__(self, capacity: int = 200) -> None:
        self._lock = threading.Lock()
        self._events: deque[dict[str, Any]] = deque(maxlen=capacity)
        self._seq = 0
        self._listeners: list[Callable[[dict], None]] = []

    def add(self, level: str, message: str, kind: str = "general") -> dict:
        if level not in self.LEVELS:
            raise InvalidInput(f"event level must be one of {self.LEVELS}, not {level!r}")
        if kind not in self.KINDS:
            raise InvalidInput(f"event kind must be one of {self.KINDS}, not {kind!r}")
        with self._lock:
            self._seq += 1
            event = {"seq": self._seq, "level": level, "kind": kind, "message": message, "time_s": time.time()}
            self._events.append(event)
            listeners = list(self._listeners)
        for listener in listeners:
            listener(event)
        return event

    def since(self, seq: int) -> list[dict]:
        """Events with seq > `seq` still held (older ones have been dropped)."""
        with self._lock:
            return [event for event in self._events if event["seq"] > seq]

    @property
    def last_seq(self) -> int:
        with self._lock:
            return self._seq

    def add_listener(self, listener: Callable[[dict], None]) -> None:
        with self._lock:
            self._listeners.append(listener)

    def remove_listener(self, listener: Callable[[dict], None]) -> None:
        with self._lock:
            if listener in self._listeners:
                self._listeners.remove(listener)
