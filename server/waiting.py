"""`?wait=true` without holding a worker thread (issue 18 item 4).

A waiting request starts its command on a worker thread as before, then awaits the end on the event loop:
one thread per app (the Waiter) checks the conditions of every waiting request every POLL_S (they read
devices and may block on their locks, so never on the event loop) and resolves each request's future;
the request meanwhile checks every DISCONNECT_POLL_S whether its client hung up, and stops waiting if so.
So 42 clients that send `?wait=true` and hang up (or stay without reading) hold no worker thread, and
status, reset and every other command answer as usual.

Device waits (arm, gripper) end at once when the e-stop latch is set, as the station's own waits do; on a
fast-mode simulation (physics advances only while someone waits) the Waiter advances it while a device
wait is pending. Timeouts are wall time; at a timeout the request answers with the state as it stands.
"""

from __future__ import annotations

import asyncio
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

from fastapi import Request

log = logging.getLogger(__name__)

POLL_S = 0.02  # how often the Waiter checks the pending conditions
DISCONNECT_POLL_S = 0.25  # how often a waiting request checks whether its client hung up


@dataclass(eq=False)
class _Wait:
    condition: Callable[[], bool]
    on_devices: bool  # ends at the latch; on a fast-mode simulation the physics must advance meanwhile
    loop: asyncio.AbstractEventLoop
    future: asyncio.Future = field(default=None)  # type: ignore[assignment]


class Waiter:
    """The one thread that checks what the waiting requests wait for (see the module doc)."""

    def __init__(self, station) -> None:
        self.station = station
        self._pending: list[_Wait] = []
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="armlab-waiter", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        """End the thread; pending waits answer with the state as it stands."""
        self._stop.set()
        self._wake.set()
        self._thread.join(5)
        with self._lock:
            pending, self._pending = self._pending, []
        for entry in pending:
            self._resolve(entry, False)

    @property
    def pending_count(self) -> int:
        with self._lock:
            return len(self._pending)

    async def until(self, request: Request, condition: Callable[[], bool], timeout_s: float, on_devices: bool) -> bool:
        """Await condition() (checked on the Waiter's thread): True when it held, False at the timeout, at
        the latch (device waits) or when the client hung up (then nobody reads the answer)."""
        loop = asyncio.get_running_loop()
        entry = _Wait(condition, on_devices, loop, loop.create_future())
        with self._lock:
            self._pending.append(entry)
        self._wake.set()
        deadline = loop.time() + timeout_s
        try:
            while True:
                remaining = deadline - loop.time()
                if remaining <= 0:
                    return False
                done, _ = await asyncio.wait({entry.future}, timeout=min(DISCONNECT_POLL_S, remaining))
                if done:
                    return bool(entry.future.result())
                if await request.is_disconnected():
                    return False
        finally:
            with self._lock:
                if entry in self._pending:
                    self._pending.remove(entry)

    def _run(self) -> None:
        while not self._stop.is_set():
            with self._lock:
                pending = list(self._pending)
            if not pending:
                self._wake.wait(1.0)
                self._wake.clear()
                continue
            latched = self.station.latch.is_set()
            for entry in pending:
                try:
                    done = bool(entry.condition())
                except Exception as error:  # noqa: BLE001 - a device that cannot be read ends the wait
                    log.info("a waiting request's condition failed: %s", error)
                    done = True
                if done or (latched and entry.on_devices):
                    with self._lock:
                        if entry in self._pending:
                            self._pending.remove(entry)
                    self._resolve(entry, done)
            self._pause(any(entry.on_devices for entry in pending))

    def _pause(self, device_wait: bool) -> None:
        """POLL_S of waiting; on a fast-mode simulation with a device wait pending, of physics."""
        sim = getattr(self.station, "sim", None)
        if device_wait and sim is not None and not sim.realtime and not self.station.latch.is_set():
            sim.wait_for(lambda: self.station.latch.is_set(), POLL_S)
        else:
            self._stop.wait(POLL_S)

    @staticmethod
    def _resolve(entry: _Wait, value: bool) -> None:
        def settle() -> None:
            if not entry.future.done():
                entry.future.set_result(value)

        try:
            entry.loop.call_soon_threadsafe(settle)
        except RuntimeError:  # the loop has closed: nobody is waiting any more
            pass


def waiter_of(request: Request) -> Waiter:
    return request.app.state.waiter


async def until_arm_still(request: Request, station, timeout_s: float) -> bool:
    """Await the end of the arm's motion (see Waiter.until)."""
    return await waiter_of(request).until(request, lambda: not station.arm.is_moving(), timeout_s, on_devices=True)


async def until_fingers_still(request: Request, station) -> bool:
    """Await the gripper's fingers coming to rest (the station's own settle test)."""
    return await waiter_of(request).until(request, station.fingers_still_check(), station.config.gripper_settle_timeout_s,
                                          on_devices=True)


async def until_step_taken(request: Request, taken, timeout_s: float) -> bool:
    """Await a planned step's end: the paused job waits at its next step again, or ended (job_control.StepTaken)."""
    return await waiter_of(request).until(request, taken.done, timeout_s, on_devices=False)


async def until_job_ended(request: Request, job, timeout_s: float) -> bool:
    """Await the end of a job (its own thread runs it and, on a fast-mode simulation, the physics)."""
    return await waiter_of(request).until(request, lambda: job.done, timeout_s, on_devices=False)
