"""SQLite persistence for the station: taught programs, calibrations, camera intrinsics, colour calibrations and job results.

`Store` is the station's database file with every table: the file itself (opening, integrity check, schema,
backups) in database.py, and one module per concept: programs.py (taught programs and the teach draft),
calibrations.py (calibrations, intrinsics, colour calibrations), jobs.py (job history),
events.py (the event log kept, and the searches of it and of the job history).
"""

from armlab.store.calibrations import CalibrationTables
from armlab.store.database import DEFAULT_DB_PATH, DamagedDatabase, DamagedRecord, NotFound, UnusableDatabase
from armlab.store.events import EventTables
from armlab.store.jobs import JobTables
from armlab.store.programs import (
    MAX_PROGRAM_NAME_CHARS,
    OwnedPrograms,
    Owner,
    Program,
    ProgramTables,
)
from armlab.store.waypoint import MAX_DWELL_S, Waypoint


class Store(ProgramTables, CalibrationTables, JobTables, EventTables):
    """The station's database file and all its tables (see Database for opening, damage and backups); the
    file's path is its only state."""


__all__ = [
    "DEFAULT_DB_PATH",
    "MAX_DWELL_S",
    "MAX_PROGRAM_NAME_CHARS",
    "DamagedDatabase",
    "DamagedRecord",
    "NotFound",
    "OwnedPrograms",
    "Owner",
    "Program",
    "Store",
    "UnusableDatabase",
    "Waypoint",
]
