"""Taught programs and the teach draft: the Waypoint and Program records and their tables.

Each program (its waypoints are in its row) is one INSERT in one transaction. The teach draft holds each
recorded waypoint from the moment it is acknowledged until teach/stop turns it into a program (one
transaction: the program is inserted and the draft emptied together), so a killed station resumes the draft.

Programs and draft rows belong to an arm and a workcell (an Owner): one file may serve the RX200 and the UR3
stations, and a station lists, resumes and repeats only its own (rows from before owners were stored belong
to an arm with as many joints). Passing no owner reads and writes every row, as before.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass

from armlab.errors import InvalidInput, WrongArm
from armlab.store import program_tree
from armlab.store.database import ROW_ERRORS, DamagedRecord, Database, NotFound
from armlab.store.waypoint import Waypoint

MAX_PROGRAM_NAME_CHARS = 100  # a program's name (the API's limit too)


@dataclass(frozen=True)
class Owner:
    """Whose programs and draft: the arm (its name and joint count) and the workcell it stands in."""

    arm: str
    workcell: str | None
    dof: int

    def owns(self, arm: str | None, workcell: str | None, joint_count: int | None) -> bool:
        """True for a row of this arm and workcell; a row stored without an owner (before schema 5) belongs
        to an arm with as many joints as its waypoints (joint_count None: unreadable, claimed so it is reported)."""
        if arm is None:
            return joint_count is None or joint_count == self.dof
        return arm == self.arm and (workcell is None or self.workcell is None or workcell == self.workcell)

    def describe(self) -> str:
        return f"{self.arm} in workcell {self.workcell}" if self.workcell else self.arm


@dataclass(frozen=True)
class Program:
    """A named, saved program; updated_s: when it was last saved or edited (time.time()). waypoints: the flat
    sequence repeat plans; steps: the step tree it expands from (program_tree: waits, gripper steps, loops,
    groups), None for a program of waypoints only (as taught: stored as the flat list it always was)."""

    id: int
    name: str
    created_s: float
    waypoints: tuple[Waypoint, ...]
    updated_s: float | None = None
    arm: str | None = None  # None: saved before programs had an owner
    workcell: str | None = None
    steps: tuple | None = None

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "name": self.name,
            "created_s": self.created_s,
            "updated_s": self.updated_s if self.updated_s is not None else self.created_s,
            "arm": self.arm,
            "workcell": self.workcell,
            "waypoints": [waypoint.to_dict() for waypoint in self.waypoints],
            "steps": program_tree.to_list(self.steps) if self.steps is not None else None,
        }


@dataclass(frozen=True)
class OwnedPrograms:
    """One owner's programs, the damaged rows of theirs left out (one line each), and how many programs other
    arms or workcells have in the same file: {(arm or None, workcell or None): count}."""

    programs: list[Program]
    skipped: list[str]
    others: dict[tuple[str | None, str | None], int]


class ProgramTables(Database):
    """The programs table and the teach draft of the station's database."""

    def save_program(self, name: str, waypoints: Sequence, clear_draft: bool = False, owner: Owner | None = None) -> Program:
        """Save a new program (of `owner`'s arm and workcell); ValueError for an empty name or no waypoints.
        waypoints: a flat list or a step tree (program_tree; checked and expanded here).
        clear_draft: empty the (owner's) teach draft in the same transaction (teach/stop: the program and the
        draft never both or neither exist)."""
        steps, waypoints = _tree_and_waypoints(waypoints)
        name, payload = _checked_program(name, waypoints, steps)
        if owner is not None and any(len(waypoint.joints_rad) != owner.dof for waypoint in waypoints):
            raise InvalidInput(f"a program of {owner.arm} has {owner.dof} joints in every waypoint")
        created_s = time.time()
        arm, workcell = (owner.arm, owner.workcell) if owner is not None else (None, None)
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(
                    "INSERT INTO programs (name, created_s, waypoints_json, updated_s, arm, workcell) VALUES (?, ?, ?, ?, ?, ?)",
                    (name, created_s, payload, created_s, arm, workcell),
                )
                program_id = int(cursor.lastrowid)
                if clear_draft:
                    connection.executemany("DELETE FROM teach_draft WHERE seq = ?", [(seq,) for seq in _draft_seqs(connection, owner)])
        finally:
            connection.close()
        return Program(program_id, name, created_s, tuple(waypoints), created_s, arm, workcell, steps)

    def update_program(self, program_id: int, name: str | None = None, waypoints: Sequence | None = None) -> Program:
        """Rename and/or replace the waypoints (a flat list or a step tree) of a program, in one transaction;
        NotFound, ValueError."""
        current = self.get_program(program_id)
        new_name = current.name if name is None else name
        if waypoints is None:
            steps, new_waypoints = current.steps, current.waypoints
        else:
            steps, new_waypoints = _tree_and_waypoints(waypoints)
        new_name, payload = _checked_program(new_name, new_waypoints, steps)
        updated_s = time.time()
        rows = self._run(
            "UPDATE programs SET name = ?, waypoints_json = ?, updated_s = ? WHERE id = ? RETURNING id",
            (new_name, payload, updated_s, int(program_id)),
        )
        if not rows:
            raise NotFound(f"no program with id {program_id}")
        return Program(current.id, new_name, current.created_s, new_waypoints, updated_s, current.arm, current.workcell, steps)

    def read_programs(self) -> tuple[list[Program], list[str]]:
        """(programs that read back, one entry per skipped damaged row), by id: every owner's."""
        owned = self.programs_of(None)
        return owned.programs, owned.skipped

    def programs_of(self, owner: Owner | None) -> OwnedPrograms:
        """`owner`'s programs by id (None: everyone's), its damaged rows skipped and reported, and how many
        programs belong to other arms or workcells (never read further: their joints mean nothing here)."""
        rows = self._run(f"SELECT {_PROGRAM_COLUMNS} FROM programs ORDER BY id", raw_text=True)
        programs, skipped, others = [], [], {}
        for row in rows:
            arm, workcell = _text(row[5]), _text(row[6])
            try:
                program = _program_from_row(row)
            except ROW_ERRORS as error:
                if owner is None or owner.owns(arm, workcell, None):
                    skipped.append(self._skip(f"program {row[0]}", error))
                else:
                    others[(arm, workcell)] = others.get((arm, workcell), 0) + 1
                continue
            if owner is None or owner.owns(arm, workcell, len(program.waypoints[0].joints_rad)):
                programs.append(program)
            else:
                others[(arm, workcell)] = others.get((arm, workcell), 0) + 1
        return OwnedPrograms(programs, skipped, others)

    def list_programs(self) -> list[Program]:
        """The programs that read back; damaged rows are logged and skipped."""
        return self.read_programs()[0]

    def get_program(self, program_id: int, owner: Owner | None = None) -> Program:
        """The program with this id; NotFound, DamagedRecord, WrongArm (owner given: it belongs to another
        arm or workcell)."""
        rows = self._run(f"SELECT {_PROGRAM_COLUMNS} FROM programs WHERE id = ?", (int(program_id),), raw_text=True)
        if not rows:
            raise NotFound(f"no program with id {program_id}")
        arm, workcell = _text(rows[0][5]), _text(rows[0][6])
        if owner is not None and arm is not None and not owner.owns(arm, workcell, None):
            raise _wrong_arm(program_id, arm, workcell, owner)
        try:
            program = _program_from_row(rows[0])
        except ROW_ERRORS as error:
            raise DamagedRecord(f"program {program_id} is damaged: {self._skip(f'program {program_id}', error)}") from error
        if owner is not None and not owner.owns(arm, workcell, len(program.waypoints[0].joints_rad)):
            raise WrongArm(f"program {program_id} has {len(program.waypoints[0].joints_rad)} joints per waypoint (taught on another "
                           f"arm); this station's arm, {owner.arm}, has {owner.dof}: its joints mean nothing here")
        return program

    def delete_program(self, program_id: int) -> None:
        """Delete a program (a damaged one too); NotFound when there is none with this id."""
        if not self._run("DELETE FROM programs WHERE id = ? RETURNING id", (int(program_id),)):
            raise NotFound(f"no program with id {program_id}")

    # The teach draft ------------------------------------------------------------------------------

    def append_draft(self, waypoint: Waypoint, owner: Owner | None = None) -> int:
        """Add a recorded waypoint to the (owner's) teach draft (committed, synchronous=FULL, before this
        returns); returns how many waypoints the draft holds."""
        arm, workcell = (owner.arm, owner.workcell) if owner is not None else (None, None)
        connection = self._connect()
        try:
            with connection:
                connection.execute(
                    "INSERT INTO teach_draft (recorded_s, waypoint_json, arm, workcell) VALUES (?, ?, ?, ?)",
                    (time.time(), json.dumps(waypoint.to_dict()), arm, workcell),
                )
                return len(_draft_seqs(connection, owner))
        finally:
            connection.close()

    def undo_draft(self, owner: Owner | None = None) -> tuple[Waypoint | None, int]:
        """Remove the newest waypoint of the (owner's) draft: (the removed waypoint or None if the draft was
        empty, how many are left)."""
        connection = self._connect()
        try:
            with connection:
                seqs = _draft_seqs(connection, owner)
                row = None
                if seqs:
                    row = connection.execute("SELECT seq, CAST(waypoint_json AS BLOB) FROM teach_draft WHERE seq = ?", (seqs[-1],)).fetchone()
                    connection.execute("DELETE FROM teach_draft WHERE seq = ?", (seqs[-1],))
                left = max(len(seqs) - 1, 0)
        finally:
            connection.close()
        if row is None:
            return None, left
        try:
            return Waypoint.from_dict(json.loads(bytes(row[1]).decode("utf-8"))), left
        except ROW_ERRORS as error:
            self._skip(f"teach draft waypoint {row[0]}", error)
            return None, left

    def read_draft(self, owner: Owner | None = None) -> tuple[list[Waypoint], list[str]]:
        """The (owner's) teach draft's waypoints in recording order (damaged rows skipped and reported)."""
        rows = self._run("SELECT seq, waypoint_json, arm, workcell FROM teach_draft ORDER BY seq", raw_text=True)
        waypoints, skipped = [], []
        for seq, data, arm, workcell in rows:
            try:
                waypoint = Waypoint.from_dict(json.loads(data.decode("utf-8")))
            except ROW_ERRORS as error:
                if owner is None or owner.owns(_text(arm), _text(workcell), None):
                    skipped.append(self._skip(f"teach draft waypoint {seq}", error))
                continue
            if owner is None or owner.owns(_text(arm), _text(workcell), len(waypoint.joints_rad)):
                waypoints.append(waypoint)
        return waypoints, skipped

    def clear_draft(self, owner: Owner | None = None) -> int:
        """Empty the (owner's) teach draft; returns how many waypoints it held."""
        connection = self._connect()
        try:
            with connection:
                seqs = _draft_seqs(connection, owner)
                connection.executemany("DELETE FROM teach_draft WHERE seq = ?", [(seq,) for seq in seqs])
        finally:
            connection.close()
        return len(seqs)


_PROGRAM_COLUMNS = "id, name, created_s, waypoints_json, updated_s, arm, workcell"


def _text(value: bytes | str | None) -> str | None:
    """A TEXT column read as bytes (raw_text) or str, as str; None stays None; bad UTF-8 → replaced characters."""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else value


def _joint_count(data: bytes | str) -> int | None:
    """How many joints a draft row's waypoint has (None: the row cannot be read)."""
    try:
        item = json.loads(data)
        return len(item["joints_rad"]) if isinstance(item, dict) and isinstance(item.get("joints_rad"), list) else None
    except ROW_ERRORS:
        return None


def _draft_seqs(connection, owner: Owner | None) -> list[int]:
    """The seq of every teach draft row of `owner` (None: all), in recording order."""
    rows = connection.execute("SELECT seq, CAST(waypoint_json AS BLOB), arm, workcell FROM teach_draft ORDER BY seq").fetchall()
    return [int(seq) for seq, data, arm, workcell in rows
            if owner is None or owner.owns(_text(arm), _text(workcell), _joint_count(bytes(data)))]


def _wrong_arm(program_id: int, arm: str, workcell: str | None, owner: Owner) -> WrongArm:
    taught = f"{arm} in workcell {workcell}" if workcell else arm
    return WrongArm(f"program {program_id} was taught on {taught}; this station is {owner.describe()}: its joints mean "
                    f"nothing here (open it on a station of that arm, or teach it again here)")


def _tree_and_waypoints(items: Sequence) -> tuple[tuple | None, tuple[Waypoint, ...]]:
    """(the step tree or None when every item is a waypoint, the flat waypoint sequence); InvalidInput."""
    items = tuple(items)
    if program_tree.is_flat(items):
        return None, items
    return items, program_tree.expand(items)


def _checked_program(name: str, waypoints: Sequence[Waypoint], steps: tuple | None = None) -> tuple[str, str]:
    """(stripped name, waypoints JSON: the flat list, or the step tree when there is one) of a program to
    write; ValueError for an empty or too long name or no waypoints."""
    name = str(name).strip()
    if not name:
        raise InvalidInput("a program needs a name")
    if len(name) > MAX_PROGRAM_NAME_CHARS:
        raise InvalidInput(f"a program name has at most {MAX_PROGRAM_NAME_CHARS} characters, this one {len(name)}")
    if not waypoints:
        raise InvalidInput("a program needs at least one waypoint: record one before saving")
    if steps is not None:
        return name, json.dumps(program_tree.to_list(steps))
    return name, json.dumps([waypoint.to_dict() for waypoint in waypoints])


def _program_from_row(row: tuple) -> Program:
    """A Program from (id, name bytes, created_s, waypoints_json bytes, updated_s, arm, workcell); raises one of
    ROW_ERRORS if damaged (waypoints of different lengths included)."""
    name, items = row[1].decode("utf-8"), json.loads(row[3].decode("utf-8"))
    if not isinstance(items, list) or not items:
        raise InvalidInput("waypoints_json is not a non-empty list")
    steps, waypoints = _tree_and_waypoints(program_tree.steps_from_list(items))
    if len({len(waypoint.joints_rad) for waypoint in waypoints}) != 1:
        raise InvalidInput("the waypoints do not all have the same number of joints")
    updated_s = float(row[4]) if len(row) > 4 and row[4] is not None else None
    arm, workcell = (_text(row[5]), _text(row[6])) if len(row) > 6 else (None, None)
    return Program(int(row[0]), name, float(row[2]), waypoints, updated_s, arm, workcell, steps)

