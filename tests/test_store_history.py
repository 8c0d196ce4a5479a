"""Issue 21 History: the event log kept in the database (schema version 7) and searched by text, level and time range,
job runs searched alike with their scores; a version-6 file is migrated and keeps its job rows; absurd ranges are
refused with the reason."""

from __future__ import annotations

import math
import sqlite3

import pytest

from armlab.errors import InvalidInput
from armlab.store import Store
from armlab.store_schema import MIGRATIONS, SCHEMA_VERSION

T0_S = 1_790_000_000.0  # 2026-09


def _version_6_file(path) -> None:
    connection = sqlite3.connect(path)
    for step in MIGRATIONS[:6]:
        connection.executescript(step)
    connection.execute("PRAGMA user_version = 6")
    with connection:
        connection.execute("INSERT INTO job_results (id, name, state, message, started_s, finished_s, result_json) "
                           "VALUES ('old', 'pick_sort', 'succeeded', 'done', ?, ?, '{\"moved\": 3}')", (T0_S, T0_S + 60))
    connection.close()


def test_a_version_6_file_is_migrated_and_keeps_its_jobs(tmp_path):
    path = tmp_path / "v6.sqlite3"
    _version_6_file(path)
    store = Store(path)
    assert sqlite3.connect(path).execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION == 7
    (job,) = store.search_jobs()
    assert job["id"] == "old" and job["result"] == {"moved": 3} and job["score"] is None
    store.record_job_score("old", {"points": 40, "max_points": 100, "breakdown": [{"rule": "sorted", "points": 40}]})
    store.record_job({"id": "old", "name": "pick_sort", "state": "succeeded", "message": "done", "started_s": T0_S,
                      "finished_s": T0_S + 60, "result": {"moved": 3}})  # a late outcome write keeps the score
    assert store.search_jobs()[0]["score"]["breakdown"][0]["points"] == 40
    assert store.job_results()[0]["id"] == "old"  # the old reader still works


def test_events_are_searched_by_text_level_and_time(tmp_path):
    store = Store(tmp_path / "events.sqlite3")
    store.add_events([
        {"time_s": T0_S + i, "level": level, "kind": "general", "message": message}
        for i, (level, message) in enumerate([("info", "station started"), ("warn", "camera moved: recalibrate"),
                                              ("error", "E-stop: motion halted"), ("info", "job 'grab' started")])
    ])
    assert [e["message"] for e in store.search_events()][0] == "job 'grab' started"  # newest first
    assert [e["message"] for e in store.search_events(text="CAMERA")] == ["camera moved: recalibrate"]
    assert [e["level"] for e in store.search_events(level="error")] == ["error"]
    assert [e["time_s"] for e in store.search_events(from_s=T0_S + 1, to_s=T0_S + 2)] == [T0_S + 2, T0_S + 1]
    assert store.search_events(text="100%_") == []  # LIKE wildcards are literal
    assert len(store.search_events(limit=2)) == 2


@pytest.mark.parametrize("bad", [
    {"from_s": T0_S + 10, "to_s": T0_S},  # from after to
    {"to_s": 1e6 * 3.15e7},  # a million years
    {"from_s": math.nan},
    {"to_s": math.inf},
    {"limit": 10**9},
    {"limit": 0},
    {"level": "debug"},
    {"from_s": -1.0},
])
def test_absurd_searches_are_refused_with_the_reason(tmp_path, bad):
    store = Store(tmp_path / "bad.sqlite3")
    with pytest.raises(InvalidInput):
        store.search_events(**bad)
