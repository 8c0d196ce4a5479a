"""The latch of the gate: e-stop, device loss and reset.

A mixin of core.Station. E-stop and device loss set the lock-free latch (`_halt`) first, cancel the job
and halt the arm and gripper without the station lock, and only then record the state under it; every
command path checks the latch before it reaches a device. Reset clears it, and is refused while a lost
device is still gone.
"""

from __future__ import annotations

import logging

from armlab.errors import CommandRefused, DeviceLost
from armlab.station.perception import DEVICE_ERRORS
from armlab.station.states import State, allowed_commands

log = logging.getLogger(__name__)


class Latch:
    """E-stop, device loss, reset."""

    def _halt_devices(self, gripper: bool = True) -> list[str]:
        """Stop the arm (and gripper); never raises (a lost device is reported). No lock needed. Counted, so a
        command checked before this halt and sent after it is halted again (motion.py _sending)."""
        self._halts += 1
        self._commanded = None  # the arm holds where it is: no commanded motion to continue
        failures = []
        for device in (self.arm, self.gripper) if gripper else (self.arm,):
            try:
                device.stop()
            except DEVICE_ERRORS as error:
                failures.append(f"{device}: {error}")
        return failures

    @property
    def latched(self) -> bool:
        """True while the e-stop (or a device loss) latch is set; lock-free."""
        return self._halt.is_set()

    def estop(self, source: str | None = None) -> None:
        """Halt now and latch, from any state and from anyone (no lease needed): latch first, cancel the
        job, stop arm and gripper, then record the state; a command that was being sent when the latch
        went up is stopped by a second halt once the lock shows it has finished."""
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel(halted=True)
        failures = self._halt_devices()
        with self._lock:
            self._jog = None
            by = f" by '{source}'" if source else ""
            self._transition("estop", source=source, detail=f"e-stop pressed{by}: reset to continue")
        failures += self._halt_devices()
        self.events.add("error", "E-stop: motion halted" + (f" ({'; '.join(sorted(set(failures)))})" if failures else ""))

    def device_problems(self) -> dict[str, str]:
        """{device: reason} for each device not answering now (reads the arm and gripper, checks the
        camera's frames); empty when all answer."""
        problems: dict[str, str] = {}
        for name, read in (("arm", self.arm.read_joint_state), ("gripper", self.gripper.read_state)):
            try:
                read()
            except DEVICE_ERRORS as error:
                problems[name] = f"{type(error).__name__}: {error}"
        if self._frame_source is not None and self._started:
            camera = self._frame_source.health(self.config.camera_timeout_s)
            if camera is not None:
                problems["camera"] = camera
        return problems

    def _on_device_problems(self, problems: dict[str, str]) -> None:
        """The device watch's report: fault on a new loss, log a recovery (the station stays in fault)."""
        with self._lock:
            new = {name: reason for name, reason in problems.items() if name not in self._lost}
            back = [name for name in self._lost if name not in problems]
            self._lost = dict(problems)
        for name in back:
            self.events.add("info", f"{name} answers again: reset to continue")
        if new:
            self.device_failed(", ".join(new), "; ".join(new.values()))

    def device_failed(self, device: str, reason: str) -> None:
        """A device is lost: latch, cancel the job, hold the arm still, enter fault with the reason."""
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel(halted=True)
        self._halt_devices()
        with self._lock:
            self._jog = None
            if self._transition("device_failed", event=True) is State.FAULT:
                self._detail = f"{device} lost: {reason}; reset once it is back"
        self.events.add("error", f"{device} lost: {reason}: motion halted")

    def component_failed(self, what: str, reason: str) -> None:
        """A part of the station died (e.g. the teach recorder's thread): latch, cancel the job, hold the arm
        still, enter fault with the reason, log it. Reset clears it (no device to wait for)."""
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel(halted=True)
        self._halt_devices()
        with self._lock:
            self._jog = None
            if self._transition("device_failed", event=True) is State.FAULT:
                self._detail = f"{what} failed: {reason}; reset to continue"
        log.error("%s failed: %s: motion halted, station in fault", what, reason)
        self.events.add("error", f"{what} failed: {reason}: motion halted")

    def reset(self, source: str | None = None) -> None:
        """Leave estop/fault for idle without moving the arm; DeviceLost while a device is still gone."""
        with self._lock:
            if self._state not in (State.ESTOP, State.FAULT):  # not while an e-stop is still being recorded
                raise CommandRefused("reset", self._effective_state().value, allowed_commands(self._effective_state()))
            self._check("reset", source)
        problems = self.device_problems()  # device reads: outside the lock
        if problems:
            with self._lock:
                self._lost.update(problems)
            raise DeviceLost("reset refused: " + "; ".join(f"the {name} is still lost ({reason})" for name, reason in problems.items()))
        with self._lock:
            self._transition("reset", source=source, detail="")
            back, self._lost = list(self._lost), {}  # the watch may not have seen them come back yet
            self._halt.clear()
        for name in back:
            self.events.add("info", f"{name} answers again")
        self.events.add("info", "reset: station idle")
