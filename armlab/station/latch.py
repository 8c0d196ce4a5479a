"""The latch of the gate: the lock-free flag e-stop, device loss and a failed part set, the halting of the arm and
gripper, and which devices are lost.

Owned by core.Station (station.latch), which sets it before any lock, halts through it, and records the state
change itself (estop, device_failed, component_failed, reset in core.py). Every command path checks it before it
reaches a device; reset clears it, refused while a lost device is still gone.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from armlab.station.perception import DEVICE_ERRORS


class Latch:
    """The flag, the halt count and the lost devices; halts `arm` and `gripper` (device.stop()).

    on_halt: called on every halt before the devices are told to stop (the gate forgets the commanded motion)."""

    def __init__(self, arm: Any, gripper: Any, on_halt: Callable[[], None] = lambda: None) -> None:
        self._arm, self._gripper, self._on_halt = arm, gripper, on_halt
        self._flag = threading.Event()  # set by e-stop and device loss (before any lock), cleared by reset
        self._halts = 0  # how many times the devices were halted: a send checked before a halt and made after it re-halts
        self._lost_lock = threading.Lock()
        self._lost: dict[str, str] = {}  # devices not answering: {name: reason}

    # The flag ---------------------------------------------------------------------------------------

    def set(self) -> None:
        self._flag.set()

    def clear(self) -> None:
        self._flag.clear()

    def is_set(self) -> bool:
        """True while the e-stop (or a device loss, a failed part) latch is set; lock-free."""
        return self._flag.is_set()

    # Halting ----------------------------------------------------------------------------------------

    @property
    def halts(self) -> int:
        """How many times halt_devices ran (motion.py _sending compares it before and after a send)."""
        return self._halts

    def halt_devices(self, gripper: bool = True) -> list[str]:
        """Stop the arm (and the gripper); never raises: a device that fails to stop is reported ("device: error").
        Counted first, so a command checked before this halt and sent after it is halted again."""
        self._halts += 1
        self._on_halt()
        failures = []
        for device in (self._arm, self._gripper) if gripper else (self._arm,):
            try:
                device.stop()
            except DEVICE_ERRORS as error:
                failures.append(f"{device}: {error}")
        return failures

    # Lost devices -----------------------------------------------------------------------------------

    def lost(self) -> dict[str, str]:
        """{device: reason} of the devices known lost (a copy)."""
        with self._lost_lock:
            return dict(self._lost)

    def note_problems(self, problems: dict[str, str]) -> tuple[dict[str, str], list[str]]:
        """The device watch's whole report: the lost set becomes `problems`; returns (newly lost {name: reason},
        names that answer again)."""
        with self._lost_lock:
            new = {name: reason for name, reason in problems.items() if name not in self._lost}
            back = [name for name in self._lost if name not in problems]
            self._lost = dict(problems)
        return new, back

    def add_lost(self, problems: dict[str, str]) -> None:
        """Devices found still lost (reset's own look): added to the lost set."""
        with self._lost_lock:
            self._lost.update(problems)

    def forget_lost(self) -> list[str]:
        """Reset: the lost set is emptied (the watch may not have seen them come back yet); returns their names."""
        with self._lost_lock:
            back, self._lost = list(self._lost), {}
        return back
