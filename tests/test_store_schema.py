"""The database schema is versioned and migrated (PRAGMA user_version), and the teach draft (issue 9)."""

import json
import sqlite3

import pytest

from armlab.store import DamagedDatabase, Store, Waypoint
from armlab.store_schema import SCHEMA_VERSION

# The schema files had before versions existed (user_version 0), with a program saved by that station.
OLD_SCHEMA = """
CREATE TABLE programs (id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL, created_s REAL NOT NULL, waypoints_json TEXT NOT NULL);
CREATE TABLE calibrations (id INTEGER PRIMARY KEY AUTOINCREMENT, created_s REAL NOT NULL, data_json TEXT NOT NULL);
CREATE TABLE job_results (id TEXT PRIMARY KEY, name TEXT NOT NULL, state TEXT NOT NULL, message TEXT NOT NULL,
                          started_s REAL NOT NULL, finished_s REAL, result_json TEXT);
"""


def _version(path) -> int:
    connection = sqlite3.connect(path)
    try:
        return connection.execute("PRAGMA user_version").fetchone()[0]
    finally:
        connection.close()


def test_an_old_file_is_migrated_and_keeps_its_programs(tmp_path):
    path = tmp_path / "old.sqlite3"
    connection = sqlite3.connect(path)
    connection.executescript(OLD_SCHEMA)
    with connection:
        connection.execute("INSERT INTO programs (name, created_s, waypoints_json) VALUES ('legacy', 12.5, ?)",
                           (json.dumps([{"joints_rad": [0.1, 0, 0, 0, 0], "gripper": "grasp"}]),))
    connection.close()
    assert _version(path) == 0
    store = Store(path)
    assert _version(path) == SCHEMA_VERSION
    (program,) = store.list_programs()
    assert program.name == "legacy" and program.updated_s == 12.5
    assert program.waypoints[0] == Waypoint((0.1, 0, 0, 0, 0), "grasp", 0.0, None)
    assert store.append_draft(Waypoint((0.0,) * 5, "release")) == 1  # the draft table exists now
    Store(path)  # opening again migrates nothing and keeps the data
    assert [p.name for p in Store(path).list_programs()] == ["legacy"]


def test_a_new_file_starts_at_the_current_version(tmp_path):
    Store(tmp_path / "new.sqlite3")
    assert _version(tmp_path / "new.sqlite3") == SCHEMA_VERSION


def test_a_file_from_a_newer_station_is_refused_naming_it(tmp_path):
    path = tmp_path / "future.sqlite3"
    Store(path)
    connection = sqlite3.connect(path)
    connection.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 5}")
    connection.close()
    with pytest.raises(DamagedDatabase, match="newer") as refused:
        Store(path)
    assert str(path) in str(refused.value)


def test_the_draft_records_undoes_and_is_emptied_with_the_save(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    first, second = Waypoint((0.1,) * 5, "release", 0.5), Waypoint((0.2,) * 5, "grasp", 0.0, 1.5)
    assert store.append_draft(first) == 1 and store.append_draft(second) == 2
    assert Store(tmp_path / "db.sqlite3").read_draft() == ([first, second], [])  # on disk
    assert store.undo_draft() == (second, 1)
    store.append_draft(second)
    program = store.save_program("taught", store.read_draft()[0], clear_draft=True)
    assert program.waypoints == (first, second) and store.read_draft() == ([], [])
    assert store.undo_draft() == (None, 0)


def test_a_refused_save_keeps_the_draft(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    store.append_draft(Waypoint((0.1,) * 5, "release"))
    with pytest.raises(ValueError, match="name"):
        store.save_program("  ", store.read_draft()[0], clear_draft=True)
    assert len(store.read_draft()[0]) == 1 and store.list_programs() == []


def test_update_program_renames_and_replaces_in_one_go(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    program = store.save_program("a", [Waypoint((0.1,) * 5, "release")])
    updated = store.update_program(program.id, name="b", waypoints=[Waypoint((0.2,) * 5, "grasp", 1.0)])
    assert store.get_program(program.id) == updated and updated.name == "b" and updated.created_s == program.created_s
    with pytest.raises(ValueError):
        store.update_program(program.id, waypoints=[])
    assert store.get_program(program.id) == updated


@pytest.mark.parametrize(("dwell_s", "moving_time_s"), [(-1.0, None), (float("nan"), None), (0.0, 0.0), (0.0, -2.0), (1e9, None)])
def test_bad_dwell_and_moving_times_are_refused(dwell_s, moving_time_s):
    with pytest.raises(ValueError):
        Waypoint((0.0,) * 5, "release", dwell_s, moving_time_s)
