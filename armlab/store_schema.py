"""The SQLite schema of the station's database and its migrations, versioned by PRAGMA user_version.

Version 0 is a file made before versions existed (or a new, empty file). Each migration takes the file
from version n-1 to n inside one transaction, together with the user_version bump, so a migration killed
half-way leaves the file at n-1 and runs again at the next start. A file newer than this code is refused.
"""

from __future__ import annotations

import sqlite3

# MIGRATIONS[n - 1] takes a file from version n - 1 to n.
MIGRATIONS: tuple[str, ...] = (
    # 1: the original tables (kept as they were: an old file already has them).
    """
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
    """,
    # 2: programs remember when they were last edited; the teach draft holds each recorded waypoint
    # from the moment the API acknowledges it until teach/stop saves the program (issue 9/10: SIGKILL).
    """
    ALTER TABLE programs ADD COLUMN updated_s REAL;
    UPDATE programs SET updated_s = created_s WHERE updated_s IS NULL;
    CREATE TABLE IF NOT EXISTS teach_draft (
        seq INTEGER PRIMARY KEY AUTOINCREMENT,
        recorded_s REAL NOT NULL,
        waypoint_json TEXT NOT NULL
    );
    """,
    # 3: intrinsics measured by the station's checkerboard capture, per camera (its name/serial and
    # image size); the newest row of a camera is the one in use (issue 11 item 4).
    """
    CREATE TABLE IF NOT EXISTS intrinsics (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        camera TEXT NOT NULL,
        created_s REAL NOT NULL,
        data_json TEXT NOT NULL
    );
    CREATE INDEX IF NOT EXISTS intrinsics_by_camera ON intrinsics (camera, id);
    """,
    # 4: the station's colour calibration (operator samples: colour name + board-normalised CIELAB,
    # armlab/station/colors.py); the newest row is the one in use, a reset stores one with no samples
    # (issue 17 item 2).
    """
    CREATE TABLE IF NOT EXISTS color_calibrations (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        created_s REAL NOT NULL,
        data_json TEXT NOT NULL
    );
    """,
    # 5: the arm's calibration from the camera (joint offsets, compliance, base pose: armlab.kinematics.
    # arm_calibration), beside the camera's; the newest row is the one in use (issue 19 item 2).
    """
    CREATE TABLE IF NOT EXISTS arm_calibrations (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        created_s REAL NOT NULL,
        data_json TEXT NOT NULL
    );
    """,
    # 6: programs and the teach draft belong to an arm and a workcell (one file shared by the RX200 and the
    # UR3 stations, issue 21 item 1). Rows from before have NULL: they belong to an arm with as many joints.
    """
    ALTER TABLE programs ADD COLUMN arm TEXT;
    ALTER TABLE programs ADD COLUMN workcell TEXT;
    ALTER TABLE teach_draft ADD COLUMN arm TEXT;
    ALTER TABLE teach_draft ADD COLUMN workcell TEXT;
    """,
    # 7: the station's event log, kept (searchable and exportable from the page's History panel, issue 21); the
    # jobs' history is searched by start time and keeps a simulated run's score with its breakdown (NULL: none).
    """
    CREATE TABLE IF NOT EXISTS events (
        id INTEGER PRIMARY KEY AUTOINCREMENT,
        time_s REAL NOT NULL,
        level TEXT NOT NULL,
        kind TEXT NOT NULL,
        message TEXT NOT NULL
    );
    CREATE INDEX IF NOT EXISTS events_by_time ON events (time_s);
    CREATE INDEX IF NOT EXISTS job_results_by_start ON job_results (started_s);
    ALTER TABLE job_results ADD COLUMN score_json TEXT;
    """,
)

SCHEMA_VERSION = len(MIGRATIONS)


class NewerSchema(RuntimeError):
    """The file was written by a newer station (its schema version is above SCHEMA_VERSION)."""


def schema_version(connection: sqlite3.Connection) -> int:
    return int(connection.execute("PRAGMA user_version").fetchone()[0])


def migrate(connection: sqlite3.Connection) -> list[int]:
    """Bring the file to SCHEMA_VERSION, one transaction per step; returns the versions applied."""
    version = schema_version(connection)
    if version > SCHEMA_VERSION:
        raise NewerSchema(f"schema version {version} is newer than this station's ({SCHEMA_VERSION}): update armlab")
    applied = []
    for target in range(version + 1, SCHEMA_VERSION + 1):
        # executescript commits first; BEGIN ... COMMIT makes the step and its version bump atomic.
        connection.executescript(f"BEGIN; {MIGRATIONS[target - 1]} PRAGMA user_version = {target}; COMMIT;")
        applied.append(target)
    return applied
