"""Teach mode of the gate: record, undo and save waypoints, each recorded waypoint on disk before it is acknowledged.

A mixin of core.Station. The waypoints being taught live only in the store's teach draft (SQLite), never
in memory: teach_record returns once the row is committed, so a waypoint the API acknowledged survives a
SIGKILL. teach_start resumes a draft left by a killed or restarted station (discard_draft=True starts
empty); teach_stop turns the draft into a program and empties it in one transaction. SQLite runs outside
the station lock; a `_teach_saving` flag keeps two teach writes from interleaving. Trajectory mode
(teach_continuous) records on its own thread at a chosen rate through the same teach_record.
"""

from __future__ import annotations

import logging
import threading
import time

import numpy as np

from armlab.errors import CommandRefused, InvalidInput, NotController, ShuttingDown
from armlab.station.states import State
from armlab.store import Owner, Program, Waypoint

RATE_LIMITS_HZ = (0.5, 20.0)

log = logging.getLogger(__name__)


class ContinuousRecorder(threading.Thread):
    """Trajectory mode: records the pose at `rate_hz` while the arm moves (a joint changed by min_change_rad
    or the gripper command changed since the last record), each record committed like teach_record, with
    moving_time_s = the time since the previous one so repeat follows the recorded pace. Ends on stop() (with
    one last record of where the arm is, if it moved since: a loaded machine's late tick must not cut the
    motion's end off the program), on leaving teach (a refused record) or at shutdown; any other failure (a locked or damaged database, a
    device error) ends it as a station fault (state, detail, event, log) that halts the arm, never silently."""

    def __init__(self, station, rate_hz: float, min_change_rad: float, source: str | None) -> None:
        super().__init__(name="teach-recorder", daemon=True)
        self.station, self.period_s, self.min_change_rad, self.source = station, 1.0 / rate_hz, min_change_rad, source
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
            self.station.component_failed("teach recorder", f"{self.error} (after {self.recorded} waypoints)")

    def _record(self) -> None:
        station = self.station
        last_q, last_gripper, last_t = station.joints_rad(), station.gripper.read_state().command, time.monotonic()
        next_t = last_t + self.period_s
        stopping = False
        while not stopping:
            stopping = self._stop_event.wait(max(0.0, next_t - time.monotonic()))
            next_t += self.period_s
            if station._closing.is_set():
                return
            q, gripper = station.joints_rad(), station.gripper.read_state().command
            if np.max(np.abs(q - last_q)) < self.min_change_rad and gripper == last_gripper:
                continue
            now = time.monotonic()
            try:
                station.teach_record(source=self.source, moving_time_s=max(self.period_s, now - last_t))
            except CommandRefused as error:
                if station.state is State.TEACH and not station.latch.is_set():
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


class TeachCommands:
    """teach_start, teach_record, teach_continuous(_stop), teach_undo, teach_stop, teach_draft."""

    @property
    def program_owner(self) -> Owner | None:
        """Whose programs and draft this station reads and writes: its arm and workcell (None: no arm, all rows)."""
        if self.model is None:
            return None
        return Owner(str(self.model.name), getattr(self.config, "workcell", None), int(self.model.dof))

    def _teach_write(self, command: str, source: str | None, write, detail):
        """Check `command` (state, latch, lease), run write() outside the lock with the teach flag held,
        then set the detail from detail(result). Returns write()'s result."""
        with self._lock:
            self._check(command, source)
            if self._teach_saving:
                raise CommandRefused(command, "teach (busy saving)", [])
            self._teach_saving = True
        try:
            result = write()
        finally:
            with self._lock:
                self._teach_saving = False
        with self._lock:
            self._transition(command, source=source, detail=detail(result))
        return result

    def teach_start(self, source: str | None = None, discard_draft: bool = False) -> list[Waypoint]:
        """Enter teach. A draft left by a station that was stopped or killed while teaching is resumed
        (its waypoints are returned) unless discard_draft. CommandRefused outside idle."""
        with self._lock:
            self._check("teach_start", source)
        self.teach_continuous_stop()  # a recorder left from a teach session that ended by e-stop stops here
        if discard_draft:
            self.store.clear_draft(self.program_owner)
        waypoints, skipped = self.store.read_draft(self.program_owner)
        count = len(waypoints)
        with self._lock:
            self._transition(
                "teach_start", source=source, detail=f"teaching: {count} waypoints" + (" (draft resumed)" if count else "")
            )
        for entry in skipped:
            self.events.add("warn", entry)
        if count:
            self.events.add("info", f"teach mode: resumed the unsaved draft of {count} waypoints")
        else:
            self.events.add("info", "teach mode: record waypoints, then stop with a name")
        return waypoints

    def teach_record(self, source: str | None = None, dwell_s: float = 0.0, moving_time_s: float | None = None) -> tuple[Waypoint, int]:
        """Add the current joints and gripper command as a waypoint, committed to the draft before this
        returns: (the waypoint, how many the draft holds). A pose no move may reach (the fingers in the board,
        the arm in itself, outside the limits) is not recorded: UnsafeTrajectory / ValueError say why."""
        self.allowed_or_raise("teach_record", source)
        q = self.joints_rad()
        try:
            self.check_pose(q)
        except ValueError as error:
            raise type(error)(f"this pose is not recorded: {error}") from None
        command = self.gripper.read_state().command
        waypoint = Waypoint(
            tuple(float(v) for v in q), command if command in ("grasp", "release") else "release", dwell_s, moving_time_s
        )
        count = self._teach_write(
            "teach_record", source, lambda: self.store.append_draft(waypoint, self.program_owner), lambda n: f"teaching: {n} waypoints"
        )
        return waypoint, count

    def teach_undo(self, source: str | None = None) -> tuple[Waypoint | None, int]:
        """Remove the newest recorded waypoint: (it, or None when the draft was empty; how many are left)."""
        removed, left = self._teach_write(
            "teach_undo", source, lambda: self.store.undo_draft(self.program_owner), lambda r: f"teaching: {r[1]} waypoints"
        )
        if removed is not None:
            self.events.add("info", f"teach: last waypoint removed ({left} left)")
        return removed, left

    def teach_continuous(self, rate_hz: float, min_change_rad: float = 0.01, source: str | None = None) -> ContinuousRecorder:
        """Start trajectory mode: record the pose at rate_hz (0.5-20 Hz) while it changes, until
        teach_continuous_stop() or teach_stop (ValueError for a bad rate or on a synchronous station)."""
        rate_hz = float(rate_hz)
        if not RATE_LIMITS_HZ[0] <= rate_hz <= RATE_LIMITS_HZ[1]:
            raise InvalidInput(f"rate_hz must be from {RATE_LIMITS_HZ[0]:g} to {RATE_LIMITS_HZ[1]:g} Hz, got {rate_hz:g}")
        if not 0.0 < float(min_change_rad) <= 1.0:
            raise InvalidInput(f"min_change_rad must be in (0, 1] rad, got {min_change_rad!r}")
        if self.synchronous:
            raise InvalidInput("continuous recording needs the real-time station (the fast-mode simulation runs no threads)")
        self.allowed_or_raise("teach_record", source)
        self.teach_continuous_stop()
        recorder = ContinuousRecorder(self, rate_hz, float(min_change_rad), source)
        with self._lock:
            self._recorder = recorder
        recorder.start()
        self.events.add("info", f"teach: recording continuously at {rate_hz:g} Hz")
        return recorder

    def teach_continuous_stop(self) -> int:
        """Stop trajectory mode (no-op when not recording); returns how many waypoints it recorded."""
        with self._lock:
            recorder, self._recorder = self._recorder, None
        if recorder is None:
            return 0
        recorder.stop()
        self.events.add("info", f"teach: continuous recording stopped ({recorder.recorded} waypoints)")
        return recorder.recorded

    @property
    def teach_recording(self) -> dict | None:
        """{rate_hz, recorded} while trajectory mode runs, else None."""
        with self._lock:
            recorder = self._recorder
        if recorder is None or not recorder.is_alive():
            return None
        return {"rate_hz": recorder.rate_hz, "recorded": recorder.recorded}

    def teach_draft(self) -> list[Waypoint]:
        """The recorded, not yet saved waypoints (the draft; kept across restarts)."""
        return self.store.read_draft(self.program_owner)[0]

    def teach_stop(self, name: str, source: str | None = None) -> Program:
        """Save the draft as a program named `name` and return to idle (ValueError for an empty name or
        no waypoints: nothing changes, teach goes on). An e-stop during the write keeps the program and the latch."""

        self.allowed_or_raise("teach_stop", source)
        self.teach_continuous_stop()  # its last record is in the draft before the save reads it

        def save() -> Program:
            waypoints, _ = self.store.read_draft(self.program_owner)
            self.check_poses([waypoint.joints_rad for waypoint in waypoints])  # a draft from before the record check
            return self.store.save_program(name, waypoints, clear_draft=True, owner=self.program_owner)

        with self._lock:
            self._check("teach_stop", source)
            if self._teach_saving:
                raise CommandRefused("teach_stop", "teach (busy saving)", [])
            self._teach_saving = True
        try:
            program = save()
        finally:
            with self._lock:
                self._teach_saving = False
        with self._lock:
            if self._effective_state() is State.TEACH:
                self._transition("teach_stop", source=source, detail="")
        self.events.add("info", f"program '{program.name}' saved ({len(program.waypoints)} waypoints)")
        return program

    def teach_exit(self, source: str | None = None) -> None:
        """Leave teach for idle without saving (CommandRefused outside teach): the draft stays on disk and
        the next teach_start resumes it (unless discard_draft). Nothing moves. Without it an empty draft,
        which teach_stop cannot save, could only be left by e-stop and reset."""
        self.allowed_or_raise("teach_stop", source)
        self.teach_continuous_stop()
        with self._lock:
            if self._teach_saving:
                raise CommandRefused("teach_stop", "teach (busy saving)", [])
            self._transition("teach_stop", source=source, detail="")
        count = len(self.teach_draft())
        self.events.add("info", f"left teach without saving ({count} waypoints kept in the draft)")
