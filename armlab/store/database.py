"""The station's database file: opening and checking it, its schema, its rolling backups, and running one
statement in one transaction (the part every table of the store shares).

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
waypoint) is logged and skipped, never hiding the others. The schema is versioned (PRAGMA user_version,
migrations in store_schema.py, applied at open).
"""

from __future__ import annotations

import json
import logging
import os
import sqlite3
from collections.abc import Sequence
from pathlib import Path

from armlab.errors import ArmlabError
from armlab.store_schema import NewerSchema, migrate

log = logging.getLogger("armlab.store")

DEFAULT_DB_PATH = Path(__file__).resolve().parents[2] / "var" / "armlab.sqlite3"

# A row that cannot be read: undecodable text, bad JSON, or values the dataclasses refuse.
ROW_ERRORS = (UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError, IndexError)


class DamagedDatabase(RuntimeError):
    """The database file fails its integrity check. The message is one line: the file, why, how to recover."""


class UnusableDatabase(RuntimeError):
    """The database file is sound but cannot be used here: it is read-only, or there is no room for the
    start-up backup. The message is one line: the file, why, what to do."""


class NotFound(ArmlabError, LookupError):
    """A stored item (program, calibration) does not exist."""


class DamagedRecord(NotFound):
    """A stored item exists but cannot be read (it is skipped in lists)."""


class Database:
    """The station's database file. Creates the file, its folder and the schema on first use.

    Raises DamagedDatabase when the file exists but is not a sound SQLite database. backups: how many
    rolling copies (<db>.bak1 newest .. .bakN) to keep; each good open makes a new one (0 = none).
    The file's path is the only state; the table classes that derive from this one add their statements.
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


def _error_code(error: sqlite3.Error) -> int | None:
    """The primary SQLite result code of an error (extended codes reduced), None if it has none."""
    code = getattr(error, "sqlite_errorcode", None)
    return None if code is None else code & 0xFF



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

