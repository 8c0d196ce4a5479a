"""SQLite persistence for the station: taught programs, calibrations and job results.

One real file (default var/armlab.sqlite3). Each call opens its own short-lived connection, so the
store is safe to use from the station's job threads and the server's threads alike.
"""

from __future__ import annotations

import json
import math
import sqlite3
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

DEFAULT_DB_PATH = Path(__file__).resolve().parents[1] / "var" / "armlab.sqlite3"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS programs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    name TEXT NOT NULL,
    created_s REAL NOT NULL,
    waypoints_json TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS calibrations (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    created_s REAL NOT NULL,
    data_json TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS job_results (
    id TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    state TEXT NOT NULL,
    message TEXT NOT NULL,
    started_s REAL NOT NULL,
    finished_s REAL,
    result_json TEXT
);
"""


class NotFound(LookupError):
    """A stored item (program, calibration) does not exist."""


@dataclass(frozen=True)
class Waypoint:
    """A taught pose: joint positions (rad) and the gripper command at that pose ('grasp'|'release')."""

    joints_rad: tuple[float, ...]
    gripper: str

    def __post_init__(self) -> None:
        if not self.joints_rad or not all(math.isfinite(float(value)) for value in self.joints_rad):
            raise ValueError("Waypoint.joints_rad must be a non-empty list of finite numbers")
        if self.gripper not in ("grasp", "release"):
            raise ValueError(f"Waypoint.gripper must be 'grasp' or 'release', not {self.gripper!r}")
        object.__setattr__(self, "joints_rad", tuple(float(value) for value in self.joints_rad))

    def to_dict(self) -> dict:
        return {"joints_rad": list(self.joints_rad), "gripper": self.gripper}


@dataclass(frozen=True)
class Program:
    """A named, saved list of waypoints."""

    id: int
    name: str
    created_s: float
    waypoints: tuple[Waypoint, ...]

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "name": self.name,
            "created_s": self.created_s,
            "waypoints": [waypoint.to_dict() for waypoint in self.waypoints],
        }


class Store:
    """The station's database file. Creates the file, its folder and the schema on first use."""

    def __init__(self, path: str | Path = DEFAULT_DB_PATH) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._connect() as connection:
            connection.executescript(_SCHEMA)

    def _connect(self) -> sqlite3.Connection:
        connection = sqlite3.connect(self.path, timeout=5.0)
        connection.execute("PRAGMA journal_mode=WAL")
        return connection

    def _run(self, sql: str, parameters: Sequence = ()) -> list[tuple]:
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(sql, parameters)
                rows = cursor.fetchall()
            return rows
        finally:
            connection.close()

    # Programs -------------------------------------------------------------------------------------

    def save_program(self, name: str, waypoints: Sequence[Waypoint]) -> Program:
        """Save a new program; ValueError for an empty name or no waypoints."""
        name = str(name).strip()
        if not name:
            raise ValueError("a program needs a name")
        if not waypoints:
            raise ValueError("a program needs at least one waypoint: record one before saving")
        created_s = time.time()
        payload = json.dumps([waypoint.to_dict() for waypoint in waypoints])
        connection = self._connect()
        try:
            with connection:
                cursor = connection.execute(
                    "INSERT INTO programs (name, created_s, waypoints_json) VALUES (?, ?, ?)",
                    (name, created_s, payload),
                )
                program_id = int(cursor.lastrowid)
        finally:
            connection.close()
        return Program(program_id, name, created_s, tuple(waypoints))

    def list_programs(self) -> list[Program]:
        rows = self._run("SELECT id, name, created_s, waypoints_json FROM programs ORDER BY id")
        return [_program_from_row(row) for row in rows]

    def get_program(self, program_id: int) -> Program:
        rows = self._run("SELECT id, name, created_s, waypoints_json FROM programs WHERE id = ?", (int(program_id),))
        if not rows:
            raise NotFound(f"no program with id {program_id}")
        return _program_from_row(rows[0])

    def delete_program(self, program_id: int) -> None:
        self.get_program(program_id)
        self._run("DELETE FROM programs WHERE id = ?", (int(program_id),))

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
        rows = self._run("SELECT data_json FROM calibrations ORDER BY id DESC LIMIT 1")
        return json.loads(rows[0][0]) if rows else None

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

    def job_results(self, limit: int = 50) -> list[dict]:
        rows = self._run(
            "SELECT id, name, state, message, started_s, finished_s, result_json FROM job_results "
            "ORDER BY started_s DESC LIMIT ?",
            (int(limit),),
        )
        return [
            {
                "id": row[0],
                "name": row[1],
                "state": row[2],
                "message": row[3],
                "started_s": row[4],
                "finished_s": row[5],
                "result": json.loads(row[6]) if row[6] else None,
            }
            for row in rows
        ]


def _program_from_row(row: tuple) -> Program:
    waypoints = tuple(Waypoint(tuple(item["joints_rad"]), item["gripper"]) for item in json.loads(row[3]))
    return Program(int(row[0]), str(row[1]), float(row[2]), waypoints)
