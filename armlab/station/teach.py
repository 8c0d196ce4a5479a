"""Teach mode of the gate: record, undo and save waypoints, each recorded waypoint on disk before it is acknowledged.

Owned by core.Station (station.teach; its teach_* methods delegate to it). The waypoints being taught live only
in the store's teach draft (SQLite), never in memory: teach_record returns once the row is committed, so a
waypoint the API acknowledged survives a SIGKILL. teach_start resumes a draft left by a killed or restarted station (discard_draft=True starts
empty); teach_stop turns the draft into a program and empties it in one transaction. SQLite runs outside
the station lock; a `saving` flag keeps two teach writes from interleaving. Trajectory mode
(teach_continuous) records on its own thread at a chosen rate through the same teach_record. What teach needs of the
gate (its checks and state changes, the arm's readings and pose checks, the fault report) comes in as callables.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from armlab.errors import CommandRefused, InvalidInput, NotController, ShuttingDown
from armlab.store import Owner, Program, Store, Waypoint

RATE_LIMITS_HZ = (0.5, 20.0)

log = logging.getLogger(__name__)


class ContinuousRecorder(threading.Thread):
    """Trajectory mode: records the pose at `rate_hz` while the arm moves (a joint changed by min_change_rad
    or the gripper command changed since the last record), each record committed like teach_record, with
    moving_time_s = the time since the previous one so repeat follows the recorded pace. Ends on stop() (with
    one last record of where the arm is, if it moved since: a loaded machine's late tick must not cut the
    motion's end off the program), on leaving teach (a refused record) or at shutdown; any other failure (a locked or damaged database, a
    device error) ends it as a station fault (state, detail, event, log) that halts the arm, never silently."""

    def __init__(self, links: TeachLinks, record: Callable[[float], object], rate_hz: float, min_change_rad: float) -> None:
        super().__init__(name="teach-recorder", daemon=True)
        self.links, self.record = links, record  # record(moving_time_s): teach_record for this recorder's controller
        self.period_s, self.min_change_rad = 1.0 / rate_hz, min_change_rad
        self.rate_hz = rate_hz
        self.recorded = 0
        self.error: str | None = None
        self._stop_event = threading.Event()

    def stop(self, timeout_s: float = 2.0) -> None:
        self._stop_event.set()
        if self is not threading.current_thread():
            self.join(timeout_s)

    def run(self) -> None:
        try:
            self._record()
        except Exception as error:  # noqa: BLE001 - recording must not just stop: the operator is told, the arm halts
            self.error = f"{type(error).__name__}: {error}"
            log.exception("teach recorder died after %d waypoints", self.recorded)
            self.links.on_failure("teach recorder", f"{self.error} (after {self.recorded} waypoints)")

    def _record(self) -> None:
        links = self.links
        last_q, last_gripper, last_t = links.read_joints(), links.read_gripper_command(), time.monotonic()
        next_t = last_t + self.period_s
        stopping = False
        while not stopping:
            stopping = self._stop_event.wait(max(0.0, next_t - time.monotonic()))
            next_t += self.period_s
            if links.closing():
                return
            q, gripper = links.read_joints(), links.read_gripper_command()
            if np.max(np.abs(q - last_q)) < self.min_change_rad and gripper == last_gripper:
                continue
            now = time.monotonic()
            try:
                self.record(max(self.period_s, now - last_t))
            except CommandRefused as error:
                if links.teaching():
                    continue  # a record or undo from the operator was being written: record at the next tick
                self.error = str(error)
                return
            except (NotController, ShuttingDown) as error:
                self.error = str(error)
                return
            except ValueError:  # a pose no move may reach (the fingers in the board, say): not a waypoint
                continue
            self.recorded += 1
            last_q, last_gripper, last_t = q, gripper, now


@dataclass(frozen=True)
class TeachLinks:
    """What teach needs of the gate, as callables (core.Station gives its own; tests give fakes).

    allowed_or_raise(command, source): the state, latch and lease check (CommandRefused, NotController, ShuttingDown);
    transition(command, source, detail, only_in_teach): the state change, checked again (only_in_teach: none unless
    still in teach); teaching(): in teach and not latched; closing(): the station shuts down; read_joints(),
    read_gripper_command(): the arm's joints (rad) and the gripper's command; check_pose(q), check_poses(poses): what
    any move is refused for (ValueError/UnsafeTrajectory); on_failure(what, reason): the station's fault; threads:
    False where nothing may run on a thread (the fast-mode simulation)."""

    allowed_or_raise: Callable[[str, str | None], None]
    transition: Callable[[str, str | None, str, bool], None]
    teaching: Callable[[], bool]
    closing: Callable[[], bool]
    read_joints: Callable[[], np.ndarray]
    read_gripper_command: Callable[[], str]
    check_pose: Callable[[np.ndarray], object]
    check_poses: Callable[[list], None]
    on_failure: Callable[[str, str], None]
    threads: bool = True


class Teach:
    """Teach mode: start, record, undo, continuous recording, save, exit (see the module doc). Its own state: whether a
    teach write is under way (`saving`) and the continuous recorder, if one runs."""

    def __init__(self, store: Store, events: Any, owner: Callable[[], Owner | None], links: TeachLinks) -> None:
        self._store, self._events, self._owner, self._links = store, events, owner, links
        self._lock = threading.Lock()
        self._saving = False  # a teach write is under way: a second one is refused, never interleaved
        self._recorder: ContinuousRecorder | None = None  # trajectory mode's thread, if running

    @property
    def has_recorder(self) -> bool:
        """True from teach_continuous until teach_continuous_stop (the thread may have ended meanwhile)."""
        with self._lock:
            return self._recorder is not None

    @contextmanager
    def _writing(self, command: str, source: str | None) -> Iterator[None]:
        """Check `command` (state, latch, lease) and take the teach flag in one step (this part's lock, then the gate's:
        never the other way round); CommandRefused ('busy saving') while another write is under way."""
        with self._lock:
            self._links.allowed_or_raise(command, source)
            if self._saving:
                raise CommandRefused(command, "teach (busy saving)", [])
            self._saving = True
        try:
            yield
        finally:
            with self._lock:
                self._saving = False

    def _write(self, command: str, source: str | None, write, detail):
        """Check `command` (state, latch, lease), run write() outside the gate's lock with the teach flag held,
        then change the state with the detail from detail(result). Returns write()'s result."""
        with self._writing(command, source):
            result = write()
        self._links.transition(command, source, detail(result), False)
        return result

    def start(self, source: str | None = None, discard_draft: bool = False) -> list[Waypoint]:
        """Enter teach. A draft left by a station that was stopped or killed while teaching is resumed
        (its waypoints are returned) unless discard_draft. CommandRefused outside idle."""
        self._links.allowed_or_raise("teach_start", source)
        self.continuous_stop()  # a recorder left from a teach session that ended by e-stop stops here
        if discard_draft:
            self._store.clear_draft(self._owner())
        waypoints, skipped = self._store.read_draft(self._owner())
        count = len(waypoints)
        self._links.transition("teach_start", source, f"teaching: {count} waypoints" + (" (draft resumed)" if count else ""), False)
        for entry in skipped:
            self._events.add("warn", entry)
        if count:
            self._events.add("info", f"teach mode: resumed the unsaved draft of {count} waypoints")
        else:
            self._events.add("info", "teach mode: record waypoints, then stop with a name")
        return waypoints

    def record(self, source: str | None = None, dwell_s: float = 0.0, moving_time_s: float | None = None) -> tuple[Waypoint, int]:
        """Add the current joints and gripper command as a waypoint, committed to the draft before this
        returns: (the waypoint, how many the draft holds). A pose no move may reach (the fingers in the board,
        the arm in itself, outside the limits) is not recorded: UnsafeTrajectory / ValueError say why."""
        self._links.allowed_or_raise("teach_record", source)
        q = self._links.read_joints()
        try:
            self._links.check_pose(q)
        except ValueError as error:
            raise type(error)(f"this pose is not recorded: {error}") from None
        command = self._links.read_gripper_command()
        waypoint = Waypoint(
            tuple(float(v) for v in q), command if command in ("grasp", "release") else "release", dwell_s, moving_time_s
        )
        count = self._write(
            "teach_record", source, lambda: self._store.append_draft(waypoint, self._owner()), lambda n: f"teaching: {n} waypoints"
        )
        return waypoint, count

    def undo(self, source: str | None = None) -> tuple[Waypoint | None, int]:
        """Remove the newest recorded waypoint: (it, or None when the draft was empty; how many are left)."""
        removed, left = self._write(
            "teach_undo", source, lambda: self._store.undo_draft(self._owner()), lambda r: f"teaching: {r[1]} waypoints"
        )
        if removed is not None:
            self._events.add("info", f"teach: last waypoint removed ({left} left)")
        return removed, left

    def continuous(self, rate_hz: float, min_change_rad: float = 0.01, source: str | None = None) -> ContinuousRecorder:
        """Start trajectory mode: record the pose at rate_hz (0.5-20 Hz) while it changes, until
        continuous_stop() or stop (ValueError for a bad rate or where nothing may run on a thread)."""
        rate_hz = float(rate_hz)
        if not RATE_LIMITS_HZ[0] <= rate_hz <= RATE_LIMITS_HZ[1]:
            raise InvalidInput(f"rate_hz must be from {RATE_LIMITS_HZ[0]:g} to {RATE_LIMITS_HZ[1]:g} Hz, got {rate_hz:g}")
        if not 0.0 < float(min_change_rad) <= 1.0:
            raise InvalidInput(f"min_change_rad must be in (0, 1] rad, got {min_change_rad!r}")
        if not self._links.threads:
            raise InvalidInput("continuous recording needs the real-time station (the fast-mode simulation runs no threads)")
        self._links.allowed_or_raise("teach_record", source)
        self.continuous_stop()
        recorder = ContinuousRecorder(self._links, lambda moving_time_s: self.record(source=source, moving_time_s=moving_time_s),
                                      rate_hz, float(min_change_rad))
        with self._lock:
            self._recorder = recorder
        recorder.start()
        self._events.add("info", f"teach: recording continuously at {rate_hz:g} Hz")
        return recorder

    def continuous_stop(self) -> int:
        """Stop trajectory mode (no-op when not recording); returns how many waypoints it recorded."""
        with self._lock:
            recorder, self._recorder = self._recorder, None
        if recorder is None:
            return 0
        recorder.stop()
        self._events.add("info", f"teach: continuous recording stopped ({recorder.recorded} waypoints)")
        return recorder.recorded

    @property
    def recording(self) -> dict | None:
        """{rate_hz, recorded} while trajectory mode runs, else None."""
        with self._lock:
            recorder = self._recorder
        if recorder is None or not recorder.is_alive():
            return None
        return {"rate_hz": recorder.rate_hz, "recorded": recorder.recorded}

    def draft(self) -> list[Waypoint]:
        """The recorded, not yet saved waypoints (the draft; kept across restarts)."""
        return self._store.read_draft(self._owner())[0]

    def stop(self, name: str, source: str | None = None) -> Program:
        """Save the draft as a program named `name` and return to idle (ValueError for an empty name or
        no waypoints: nothing changes, teach goes on). An e-stop during the write keeps the program and the latch."""
        self._links.allowed_or_raise("teach_stop", source)
        self.continuous_stop()  # its last record is in the draft before the save reads it
        with self._writing("teach_stop", source):
            waypoints, _ = self._store.read_draft(self._owner())
            self._links.check_poses([waypoint.joints_rad for waypoint in waypoints])  # a draft from before the record check
            program = self._store.save_program(name, waypoints, clear_draft=True, owner=self._owner())
        self._links.transition("teach_stop", source, "", True)
        self._events.add("info", f"program '{program.name}' saved ({len(program.waypoints)} waypoints)")
        return program

    def exit(self, source: str | None = None) -> None:
        """Leave teach for idle without saving (CommandRefused outside teach): the draft stays on disk and
        the next start resumes it (unless discard_draft). Nothing moves. Without it an empty draft,
        which stop cannot save, could only be left by e-stop and reset."""
        self._links.allowed_or_raise("teach_stop", source)
        self.continuous_stop()
        with self._lock:
            if self._saving:
                raise CommandRefused("teach_stop", "teach (busy saving)", [])
            self._links.transition("teach_stop", source, "", False)
        count = len(self.draft())
        self._events.add("info", f"left teach without saving ({count} waypoints kept in the draft)")
