"""Taught programs and the teach draft: the Waypoint and Program records and their tables.

Each program (its waypoints are in its row) is one INSERT in one transaction. The teach draft holds each
recorded waypoint from the moment it is acknowledged until teach/stop turns it into a program (one
transaction: the program is inserted and the draft emptied together), so a killed station resumes the draft.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

from armlab.errors import InvalidInput
from armlab.store.database import ROW_ERRORS, DamagedRecord, Database, NotFound

MAX_PROGRAM_NAME_CHARS = 100  # a program's name (the API's limit too)
MAX_DWELL_S = 3600.0  # the longest dwell or moving time of one waypoint


@dataclass(frozen=True)
class Waypoint:
    """A taught pose: joint positions (rad), the gripper command at that pose ('grasp'|'release'),
    how long to hold still there (dwell_s) and, optionally, how long the move to it should take
    (moving_time_s; None = as fast as the speed override and the joint limits allow)."""

    joints_rad: tuple[float, ...]
    gripper: str
    dwell_s: float = 0.0
    moving_time_s: float | None = None

    def __post_init__(self) -> None:
        if not self.joints_rad or not all(math.isfinite(float(value)) for value in self.joints_rad):
            raise InvalidInput("Waypoint.joints_rad must be a non-empty list of finite numbers")
        if self.gripper not in ("grasp", "release"):
            raise InvalidInput(f"Waypoint.gripper must be 'grasp' or 'release', not {self.gripper!r}")
        dwell = float(self.dwell_s)
        if not math.isfinite(dwell) or not 0.0 <= dwell <= MAX_DWELL_S:
            raise InvalidInput(f"Waypoint.dwell_s must be from 0 to {MAX_DWELL_S:g} s, not {self.dwell_s!r}")
        if self.moving_time_s is not None:
            moving = float(self.moving_time_s)
            if not math.isfinite(moving) or not 0.0 < moving <= MAX_DWELL_S:
                raise InvalidInput(f"Waypoint.moving_time_s must be above 0 and at most {MAX_DWELL_S:g} s, not {self.moving_time_s!r}")
            object.__setattr__(self, "moving_time_s", moving)
        object.__setattr__(self, "joints_rad", tuple(float(value) for value in self.joints_rad))
        object.__setattr__(self, "dwell_s", dwell)

    def to_dict(self) -> dict:
        return {"joints_rad": list(self.joints_rad), "gripper": self.gripper, "dwell_s": self.dwell_s, "moving_time_s": self.moving_time_s}

    @classmethod
    def from_dict(cls, item: dict) -> Waypoint:
        """From to_dict()'s form (dwell_s and moving_time_s optional); KeyError/TypeError/ValueError if invalid."""
        if not isinstance(item, dict):
            raise TypeError("a waypoint must be a JSON object")
        return cls(tuple(item["joints_rad"]), item["gripper"], item.get("dwell_s") or 0.0, item.get("moving_time_s"))


@dataclass(frozen=True)
class Program:
    """A named, saved list of waypoints; updated_s: when it was last saved or edited (time.time())."""

    id: int
    name: str
    created_s: float
    waypoints: tuple[Waypoint, ...]
    updated_s: float | None = None

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "name": self.name,
            "created_s": self.created_s,
            "updated_s": self.updated_s if self.updated_s is not None else self.created_s,
            "waypoints": [waypoint.to_dict() for waypoint in self.waypoints],
        }


class ProgramTables(Database):
    """The programs table and the teach draft of the station's database."""

    def save_program(self, name: str, waypoints: Sequence[Waypoint], clear_draft: bool = False) -> Program:
        """Save a new program; ValueError for an empty name or no waypoints. clear_draft: empty the teach
        draft in the same transaction (teach/stop: the program and the draft never both or neither exist)."""
        name, payload = _checked_program(name, waypoints)
        created_s = time.time()
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(
                    "INSERT INTO programs (name, created_s, waypoints_json, updated_s) VALUES (?, ?, ?, ?)",
                    (name, created_s, payload, created_s),
                )
                program_id = int(cursor.lastrowid)
                if clear_draft:
                    connection.execute("DELETE FROM teach_draft")
        finally:
            connection.close()
        return Program(program_id, name, created_s, tuple(waypoints), created_s)

    def update_program(self, program_id: int, name: str | None = None, waypoints: Sequence[Waypoint] | None = None) -> Program:
        """Rename and/or replace the waypoints of a program, in one transaction; NotFound, ValueError."""
        current = self.get_program(program_id)
        new_name = current.name if name is None else name
        new_waypoints = current.waypoints if waypoints is None else tuple(waypoints)
        new_name, payload = _checked_program(new_name, new_waypoints)
        updated_s = time.time()
        rows = self._run(
            "UPDATE programs SET name = ?, waypoints_json = ?, updated_s = ? WHERE id = ? RETURNING id",
            (new_name, payload, updated_s, int(program_id)),
        )
        if not rows:
            raise NotFound(f"no program with id {program_id}")
        return Program(current.id, new_name, current.created_s, new_waypoints, updated_s)

    def read_programs(self) -> tuple[list[Program], list[str]]:
        """(programs that read back, one entry per skipped damaged row), by id."""
        rows = self._run("SELECT id, name, created_s, waypoints_json, updated_s FROM programs ORDER BY id", raw_text=True)
        programs, skipped = [], []
        for row in rows:
            try:
                programs.append(_program_from_row(row))
            except ROW_ERRORS as error:
                skipped.append(self._skip(f"program {row[0]}", error))
        return programs, skipped

    def list_programs(self) -> list[Program]:
        """The programs that read back; damaged rows are logged and skipped."""
        return self.read_programs()[0]

    def get_program(self, program_id: int) -> Program:
        rows = self._run(
            "SELECT id, name, created_s, waypoints_json, updated_s FROM programs WHERE id = ?", (int(program_id),), raw_text=True
        )
        if not rows:
            raise NotFound(f"no program with id {program_id}")
        try:
            return _program_from_row(rows[0])
        except ROW_ERRORS as error:
            raise DamagedRecord(f"program {program_id} is damaged: {self._skip(f'program {program_id}', error)}") from error

    def delete_program(self, program_id: int) -> None:
        """Delete a program (a damaged one too); NotFound when there is none with this id."""
        if not self._run("DELETE FROM programs WHERE id = ? RETURNING id", (int(program_id),)):
            raise NotFound(f"no program with id {program_id}")

    # The teach draft ------------------------------------------------------------------------------

    def append_draft(self, waypoint: Waypoint) -> int:
        """Add a recorded waypoint to the teach draft (committed, synchronous=FULL, before this returns);
        returns how many waypoints the draft holds."""
        connection = self._connect()
        try:
            with connection:
                connection.execute(
                    "INSERT INTO teach_draft (recorded_s, waypoint_json) VALUES (?, ?)", (time.time(), json.dumps(waypoint.to_dict()))
                )
                return int(connection.execute("SELECT count(*) FROM teach_draft").fetchone()[0])
        finally:
            connection.close()

    def undo_draft(self) -> tuple[Waypoint | None, int]:
        """Remove the newest waypoint of the draft: (the removed waypoint or None if the draft was empty, how many are left)."""
        connection = self._connect()
        connection.text_factory = bytes
        try:
            with connection:
                row = connection.execute("SELECT seq, waypoint_json FROM teach_draft ORDER BY seq DESC LIMIT 1").fetchone()
                if row is not None:
                    connection.execute("DELETE FROM teach_draft WHERE seq = ?", (row[0],))
                left = int(connection.execute("SELECT count(*) FROM teach_draft").fetchone()[0])
        finally:
            connection.close()
        if row is None:
            return None, left
        try:
            return Waypoint.from_dict(json.loads(row[1].decode("utf-8"))), left
        except ROW_ERRORS as error:
            self._skip(f"teach draft waypoint {row[0]}", error)
            return None, left

    def read_draft(self) -> tuple[list[Waypoint], list[str]]:
        """The teach draft's waypoints in recording order (damaged rows skipped and reported)."""
        rows = self._run("SELECT seq, waypoint_json FROM teach_draft ORDER BY seq", raw_text=True)
        waypoints, skipped = [], []
        for seq, data in rows:
            try:
                waypoints.append(Waypoint.from_dict(json.loads(data.decode("utf-8"))))
            except ROW_ERRORS as error:
                skipped.append(self._skip(f"teach draft waypoint {seq}", error))
        return waypoints, skipped

    def clear_draft(self) -> int:
        """Empty the teach draft; returns how many waypoints it held."""
        return len(self._run("DELETE FROM teach_draft RETURNING seq"))


def _checked_program(name: str, waypoints: Sequence[Waypoint]) -> tuple[str, str]:
    """(stripped name, waypoints JSON) of a program to write; ValueError for an empty or too long name or
    no waypoints."""
    name = str(name).strip()
    if not name:
        raise InvalidInput("a program needs a name")
    if len(name) > MAX_PROGRAM_NAME_CHARS:
        raise InvalidInput(f"a program name has at most {MAX_PROGRAM_NAME_CHARS} characters, this one {len(name)}")
    if not waypoints:
        raise InvalidInput("a program needs at least one waypoint: record one before saving")
    return name, json.dumps([waypoint.to_dict() for waypoint in waypoints])


def _program_from_row(row: tuple) -> Program:
    """A Program from (id, name bytes, created_s, waypoints_json bytes, updated_s); raises one of ROW_ERRORS if damaged."""
    name, items = row[1].decode("utf-8"), json.loads(row[3].decode("utf-8"))
    if not isinstance(items, list) or not items:
        raise InvalidInput("waypoints_json is not a non-empty list")
    waypoints = tuple(Waypoint.from_dict(item) for item in items)
    updated_s = float(row[4]) if len(row) > 4 and row[4] is not None else None
    return Program(int(row[0]), name, float(row[2]), waypoints, updated_s)

