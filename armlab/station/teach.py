"""Teach mode of the gate: record, undo and save waypoints, each recorded waypoint on disk before it is acknowledged.

A mixin of core.Station. The waypoints being taught live only in the store's teach draft (SQLite), never
in memory: teach_record returns once the row is committed, so a waypoint the API acknowledged survives a
SIGKILL. teach_start resumes a draft left by a killed or restarted station (discard_draft=True starts
empty); teach_stop turns the draft into a program and empties it in one transaction. SQLite runs outside
the station lock; a `_teach_saving` flag keeps two teach writes from interleaving.
"""

from __future__ import annotations

from armlab.errors import CommandRefused
from armlab.station.states import State
from armlab.store import Program, Waypoint


class TeachCommands:
    """teach_start, teach_record, teach_undo, teach_stop, teach_draft."""

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
        if discard_draft:
            self.store.clear_draft()
        waypoints, skipped = self.store.read_draft()
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
        returns: (the waypoint, how many the draft holds)."""
        self.allowed_or_raise("teach_record", source)
        q = self.joints_rad()
        command = self.gripper.read_state().command
        waypoint = Waypoint(
            tuple(float(v) for v in q), command if command in ("grasp", "release") else "release", dwell_s, moving_time_s
        )
        count = self._teach_write(
            "teach_record", source, lambda: self.store.append_draft(waypoint), lambda n: f"teaching: {n} waypoints"
        )
        return waypoint, count

    def teach_undo(self, source: str | None = None) -> tuple[Waypoint | None, int]:
        """Remove the newest recorded waypoint: (it, or None when the draft was empty; how many are left)."""
        removed, left = self._teach_write("teach_undo", source, self.store.undo_draft, lambda r: f"teaching: {r[1]} waypoints")
        if removed is not None:
            self.events.add("info", f"teach: last waypoint removed ({left} left)")
        return removed, left

    def teach_draft(self) -> list[Waypoint]:
        """The recorded, not yet saved waypoints (the draft; kept across restarts)."""
        return self.store.read_draft()[0]

    def teach_stop(self, name: str, source: str | None = None) -> Program:
        """Save the draft as a program named `name` and return to idle (ValueError for an empty name or
        no waypoints: nothing changes, teach goes on). An e-stop during the write keeps the program and the latch."""

        def save() -> Program:
            waypoints, _ = self.store.read_draft()
            return self.store.save_program(name, waypoints, clear_draft=True)

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
