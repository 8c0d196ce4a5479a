"""SQLite persistence for the station: taught programs, calibrations, camera intrinsics, colour calibrations and job results.

One real file (default var/armlab.sqlite3). Each call opens its own short-lived connection, so the
store is safe to use from the station's job threads and the server's threads alike.

Damaged data: opening runs `PRAGMA quick_check` and refuses a damaged file with DamagedDatabase, a
one-line message naming the file and the newest good backup. A 0-byte file that already exists is
damaged: SQLite writes its header on the first statement, so a database is never empty once created
(a first start killed before that leaves 0 bytes: delete the file). Only a missing file is new. A sound
file that cannot be written (read-only), or no room for the start-up backup, is UnusableDatabase saying so
(never "damaged"), and no partial backup is left.
With backups=N, each good open first copies the file to <db>.bak1 with SQLite's backup API, shifting
older copies to .bak2 .. .bakN. A single row that cannot be read (bad UTF-8, bad JSON, an invalid
waypoint) is logged and skipped, never hiding the others. Each program (its waypoints are in its
row) and each calibration is one INSERT in one transaction. The schema is versioned (PRAGMA user_version,
migrations in store_schema.py, applied at open). The teach draft holds each recorded waypoint from the
moment it is acknowledged until teach/stop turns it into a program (one transaction: the program is
inserted and the draft emptied together), so a killed station resumes the draft.
"""

from __future__ import annotations

import json
import logging
import math
import os
import sqlite3
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from armlab.store_schema import NewerSchema, migrate

log = logging.getLogger(__name__)

MAX_PROGRAM_NAME_CHARS = 100  # a program's name (the API's limit too)

DEFAULT_DB_PATH = Path(__file__).resolve().parents[1] / "var" / "armlab.sqlite3"
MAX_DWELL_S = 3600.0  # the longest dwell or moving time of one waypoint

# A row that cannot be read: undecodable text, bad JSON, or values the dataclasses refuse.
_ROW_ERRORS = (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError, IndexError)


class DamagedDatabase(RuntimeError):
    """The database file fails its integrity check. The message is one line: the file, why, how to recover."""


class UnusableDatabase(RuntimeError):
    """The database file is sound but cannot be used here: it is read-only, or there is no room for the
    start-up backup. The message is one line: the file, why, what to do."""


class NotFound(LookupError):
    """A stored item (program, calibration) does not exist."""


class DamagedRecord(NotFound):
    """A stored item exists but cannot be read (it is skipped in lists)."""


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
            raise ValueError("Waypoint.joints_rad must be a non-empty list of finite numbers")
        if self.gripper not in ("grasp", "release"):
            raise ValueError(f"Waypoint.gripper must be 'grasp' or 'release', not {self.gripper!r}")
        dwell = float(self.dwell_s)
        if not math.isfinite(dwell) or not 0.0 <= dwell <= MAX_DWELL_S:
            raise ValueError(f"Waypoint.dwell_s must be from 0 to {MAX_DWELL_S:g} s, not {self.dwell_s!r}")
        if self.moving_time_s is not None:
            moving = float(self.moving_time_s)
            if not math.isfinite(moving) or not 0.0 < moving <= MAX_DWELL_S:
                raise ValueError(f"Waypoint.moving_time_s must be above 0 and at most {MAX_DWELL_S:g} s, not {self.moving_time_s!r}")
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


class Store:
    """The station's database file. Creates the file, its folder and the schema on first use.

    Raises DamagedDatabase when the file exists but is not a sound SQLite database. backups: how many
    rolling copies (<db>.bak1 newest .. .bakN) to keep; each good open makes a new one (0 = none).
    """

    def __init__(self, path: str | Path = DEFAULT_DB_PATH, backups: int = 0) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._check()
        if backups > 0:
            self._rolling_backup(backups)

    def _connect(self) -> sqlite3.Connection:
        connection = sqlite3.connect(self.path, timeout=5.0)
        connection.execute("PRAGMA journal_mode=WAL")
        connection.execute("PRAGMA synchronous=FULL")  # an acknowledged write survives a power cut too
        return connection

    def backup_path(self, index: int) -> Path:
        return self.path.with_name(f"{self.path.name}.bak{index}")

    def _check(self) -> None:
        """Create the schema in a new file; refuse an existing file that fails PRAGMA quick_check."""
        if self.path.exists() and self.path.stat().st_size == 0:
            self._refuse("it is empty (0 bytes) although it exists: a truncated database")
        try:
            connection = self._connect()
            try:
                rows = connection.execute("PRAGMA quick_check").fetchall()
                if [tuple(row) for row in rows] != [("ok",)]:
                    problems = "; ".join(str(row[0]) for row in rows[:3])
                    self._refuse(f"PRAGMA quick_check found damage: {problems}")
                applied = migrate(connection)
                if applied:
                    log.info("database '%s' migrated to schema version %d", self.path, applied[-1])
            finally:
                connection.close()
        except NewerSchema as error:
            raise DamagedDatabase(f"database '{self.path}' cannot be used: {error}") from error
        except sqlite3.DatabaseError as error:
            if _error_code(error) in (sqlite3.SQLITE_READONLY, sqlite3.SQLITE_CANTOPEN, sqlite3.SQLITE_PERM):
                raise UnusableDatabase(
                    f"database '{self.path}' is read-only here ({error}): the station writes to it; make the file and "
                    f"its folder '{self.path.parent}' writable for this user, or give a writable --db"
                ) from None
            self._refuse(str(error))

    def _refuse(self, reason: str):
        reason = " ".join(reason.split())[:200]
        backup = self._newest_good_backup()
        if backup is not None:
            recover = (
                f"to recover, stop the station, remove '{self.path}-wal' and '{self.path}-shm' if present, "
                f"and copy the last good backup over it: cp '{backup}' '{self.path}'"
            )
        else:
            recover = f"no good backup exists; move '{self.path}' away to start with an empty database"
        raise DamagedDatabase(f"database '{self.path}' is damaged ({reason}); {recover}")

    def _newest_good_backup(self) -> Path | None:
        index = 1
        while (candidate := self.backup_path(index)).exists():
            if _passes_quick_check(candidate):
                return candidate
            index += 1
        return None

    def _rolling_backup(self, keep: int) -> None:
        """Copy the (checked) file to .bak1 with the backup API; older copies shift up; keep `keep`."""
        temporary = self.path.with_name(f"{self.path.name}.bak-new")
        try:
            source, target = self._connect(), sqlite3.connect(temporary)
            try:
                source.backup(target)
                target.execute("PRAGMA journal_mode=DELETE")  # a backup is one self-contained file (no -wal)
            finally:
                target.close()
                source.close()
        except (sqlite3.Error, OSError) as error:  # no room (disk full, a file size limit), or not writable
            for partial in (temporary, Path(f"{temporary}-journal")):
                partial.unlink(missing_ok=True)
            raise UnusableDatabase(
                f"database '{self.path}': the start-up backup '{temporary}' could not be written ({error}); the database "
                f"is untouched: free some space in '{self.path.parent}', or set database_backups: 0 to start without one"
            ) from None
        self.backup_path(keep).unlink(missing_ok=True)
        for index in range(keep - 1, 0, -1):
            if self.backup_path(index).exists():
                os.replace(self.backup_path(index), self.backup_path(index + 1))
        os.replace(temporary, self.backup_path(1))
        for extra in range(keep + 1, keep + 100):  # copies beyond a lowered `keep`
            if not self.backup_path(extra).exists():
                break
            self.backup_path(extra).unlink()

    def _run(self, sql: str, parameters: Sequence = (), raw_text: bool = False) -> list[tuple]:
        """Rows of one statement in one transaction; raw_text: TEXT columns come back as bytes (decoded per row)."""
        connection = self._connect()
        if raw_text:
            connection.text_factory = bytes
        try:
            with connection:
                cursor = connection.execute(sql, parameters)
                rows = cursor.fetchall()
            return rows
        finally:
            connection.close()

    def _skip(self, what: str, error: Exception) -> str:
        """Log a row that cannot be read and return the one-line entry that reports it."""
        reason = "bad UTF-8" if isinstance(error, UnicodeDecodeError) else (
            "bad JSON" if isinstance(error, json.JSONDecodeError) else "invalid data"
        )
        entry = f"{what} in '{self.path}' skipped: {reason} ({type(error).__name__}: {str(error)[:120]})"
        log.warning("%s", entry)
        return entry

    # Programs -------------------------------------------------------------------------------------

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
            except _ROW_ERRORS as error:
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
        except _ROW_ERRORS as error:
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
        except _ROW_ERRORS as error:
            self._skip(f"teach draft waypoint {row[0]}", error)
            return None, left

    def read_draft(self) -> tuple[list[Waypoint], list[str]]:
        """The teach draft's waypoints in recording order (damaged rows skipped and reported)."""
        rows = self._run("SELECT seq, waypoint_json FROM teach_draft ORDER BY seq", raw_text=True)
        waypoints, skipped = [], []
        for seq, data in rows:
            try:
                waypoints.append(Waypoint.from_dict(json.loads(data.decode("utf-8"))))
            except _ROW_ERRORS as error:
                skipped.append(self._skip(f"teach draft waypoint {seq}", error))
        return waypoints, skipped

    def clear_draft(self) -> int:
        """Empty the teach draft; returns how many waypoints it held."""
        return len(self._run("DELETE FROM teach_draft RETURNING seq"))

    # Calibrations ---------------------------------------------------------------------------------

    def save_calibration(self, data: dict) -> int:
        """Save a calibration (its JSON dict); returns its id."""
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(
                    "INSERT INTO calibrations (created_s, data_json) VALUES (?, ?)", (time.time(), json.dumps(data))
                )
                return int(cursor.lastrowid)
        finally:
            connection.close()

    def latest_calibration(self) -> dict | None:
        """The newest calibration that reads back (damaged rows are logged and skipped), else None."""
        rows = self._run("SELECT id, data_json FROM calibrations ORDER BY id DESC LIMIT 20", raw_text=True)
        for calibration_id, data in rows:
            try:
                value = json.loads(data.decode("utf-8"))
                if not isinstance(value, dict):
                    raise ValueError("not a JSON object")
                return value
            except _ROW_ERRORS as error:
                self._skip(f"calibration {calibration_id}", error)
        return None

    # Intrinsics ----------------------------------------------------------------------------------

    def save_intrinsics(self, camera: str, data: dict) -> int:
        """Save measured intrinsics (their JSON dict) for a camera key; returns the row id."""
        rows = self._run("INSERT INTO intrinsics (camera, created_s, data_json) VALUES (?, ?, ?) RETURNING id",
                         (camera, time.time(), json.dumps(data)))
        return int(rows[0][0])

    def latest_intrinsics(self, camera: str) -> dict | None:
        """The newest intrinsics of a camera key that read back ({"created_s", **data}; damaged rows are
        logged and skipped), else None."""
        rows = self._run("SELECT id, created_s, data_json FROM intrinsics WHERE camera = ? ORDER BY id DESC LIMIT 20",
                         (camera,), raw_text=True)
        for row_id, created_s, data in rows:
            try:
                value = json.loads(data.decode("utf-8"))
                if not isinstance(value, dict):
                    raise ValueError("not a JSON object")
                return {**value, "created_s": float(created_s)}
            except _ROW_ERRORS as error:
                self._skip(f"intrinsics {row_id}", error)
        return None

    # Colour calibration ---------------------------------------------------------------------------

    def save_color_calibration(self, data: dict) -> int:
        """Save the station's colour calibration (its JSON dict: {"samples": [...]}); returns the row id."""
        rows = self._run("INSERT INTO color_calibrations (created_s, data_json) VALUES (?, ?) RETURNING id",
                         (time.time(), json.dumps(data)))
        return int(rows[0][0])

    def latest_color_calibration(self) -> dict | None:
        """The newest colour calibration that reads back ({"created_s", **data}; damaged rows are logged
        and skipped), else None."""
        rows = self._run("SELECT id, created_s, data_json FROM color_calibrations ORDER BY id DESC LIMIT 20", raw_text=True)
        for row_id, created_s, data in rows:
            try:
                value = json.loads(data.decode("utf-8"))
                if not isinstance(value, dict):
                    raise ValueError("not a JSON object")
                return {**value, "created_s": float(created_s)}
            except _ROW_ERRORS as error:
                self._skip(f"colour calibration {row_id}", error)
        return None

    # Job results ----------------------------------------------------------------------------------

    def record_job(self, job: dict) -> None:
        """Insert or update a job's outcome (the dict of Job.to_dict())."""
        self._run(
            "INSERT OR REPLACE INTO job_results (id, name, state, message, started_s, finished_s, result_json) "
            "VALUES (?, ?, ?, ?, ?, ?, ?)",
            (
                job["id"],
                job["name"],
                job["state"],
                job.get("message") or "",
                job["started_s"],
                job.get("finished_s"),
                json.dumps(job.get("result"), default=str),
            ),
        )

    def record_job_start(self, job: dict) -> None:
        """A job's row as it starts (state running), unless its outcome is already in: a station killed
        mid-job leaves this row, which mark_interrupted_jobs turns into 'interrupted' at the next start."""
        self._run(
            "INSERT OR IGNORE INTO job_results (id, name, state, message, started_s, finished_s, result_json) "
            "VALUES (?, ?, ?, ?, ?, NULL, 'null')",
            (job["id"], job["name"], job["state"], job.get("message") or "", job["started_s"]),
        )

    def mark_interrupted_jobs(self) -> int:
        """At start-up: jobs still 'running' were cut off by a kill, crash or power loss; they become
        'interrupted'. Returns how many."""
        rows = self._run(
            "UPDATE job_results SET state = 'interrupted', message = ? WHERE state = 'running' RETURNING id",
            ("the station stopped while this job ran (killed, crashed or lost power)",),
        )
        return len(rows)

    def job_results(self, limit: int = 50) -> list[dict]:
        """The newest job outcomes; damaged rows are logged and skipped."""
        rows = self._run(
            "SELECT id, name, state, message, started_s, finished_s, result_json FROM job_results "
            "ORDER BY started_s DESC LIMIT ?",
            (int(limit),),
            raw_text=True,
        )
        results = []
        for row in rows:
            try:
                text = [value.decode("utf-8") if isinstance(value, bytes) else value for value in row]
                results.append(
                    {
                        "id": text[0],
                        "name": text[1],
                        "state": text[2],
                        "message": text[3],
                        "started_s": float(text[4]),
                        "finished_s": None if text[5] is None else float(text[5]),
                        "result": json.loads(text[6]) if text[6] else None,
                    }
                )
            except _ROW_ERRORS as error:
                self._skip(f"job result {row[0]!r}", error)
        return results


def _checked_program(name: str, waypoints: Sequence[Waypoint]) -> tuple[str, str]:
    """(stripped name, waypoints JSON) of a program to write; ValueError for an empty or too long name or
    no waypoints."""
    name = str(name).strip()
    if not name:
        raise ValueError("a program needs a name")
    if len(name) > MAX_PROGRAM_NAME_CHARS:
        raise ValueError(f"a program name has at most {MAX_PROGRAM_NAME_CHARS} characters, this one {len(name)}")
    if not waypoints:
        raise ValueError("a program needs at least one waypoint: record one before saving")
    return name, json.dumps([waypoint.to_dict() for waypoint in waypoints])


def _error_code(error: sqlite3.Error) -> int | None:
    """The primary SQLite result code of an error (extended codes reduced), None if it has none."""
    code = getattr(error, "sqlite_errorcode", None)
    return None if code is None else code & 0xFF


def _program_from_row(row: tuple) -> Program:
    """A Program from (id, name bytes, created_s, waypoints_json bytes, updated_s); raises one of _ROW_ERRORS if damaged."""
    name, items = row[1].decode("utf-8"), json.loads(row[3].decode("utf-8"))
    if not isinstance(items, list) or not items:
        raise ValueError("waypoints_json is not a non-empty list")
    waypoints = tuple(Waypoint.from_dict(item) for item in items)
    updated_s = float(row[4]) if len(row) > 4 and row[4] is not None else None
    return Program(int(row[0]), name, float(row[2]), waypoints, updated_s)


def _passes_quick_check(path: Path) -> bool:
    """True when `path` opens read-only as SQLite and PRAGMA quick_check says ok."""
    try:
        connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        try:
            return connection.execute("PRAGMA quick_check").fetchall() == [("ok",)]
        finally:
            connection.close()
    except sqlite3.DatabaseError:
        return False
