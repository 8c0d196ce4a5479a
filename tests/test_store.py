"""The SQLite store: programs, calibrations and job results survive reopening the file."""

import math

import pytest

from armlab.store import NotFound, Store, Waypoint


def test_programs_persist_across_store_instances(tmp_path):
    path = tmp_path / "sub" / "station.sqlite3"
    first = Store(path)
    saved = first.save_program("wave", [Waypoint((0.0, 0.1, 0.2, 0.3, 0.4), "release"), Waypoint((0.5, 0, 0, 0, 0), "grasp")])
    reopened = Store(path)
    programs = reopened.list_programs()
    assert [p.name for p in programs] == ["wave"]
    assert programs[0].id == saved.id
    assert programs[0].waypoints[0].joints_rad == (0.0, 0.1, 0.2, 0.3, 0.4)
    assert programs[0].waypoints[1].gripper == "grasp"
    assert reopened.get_program(saved.id).to_dict() == saved.to_dict()


def test_program_ids_increase_and_delete_removes(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    a = store.save_program("a", [Waypoint((0.0,), "release")])
    b = store.save_program("b", [Waypoint((1.0,), "grasp")])
    assert b.id > a.id
    store.delete_program(a.id)
    assert [p.name for p in store.list_programs()] == ["b"]
    with pytest.raises(NotFound, match=str(a.id)):
        store.get_program(a.id)


@pytest.mark.parametrize(
    ("name", "waypoints", "message"),
    [
        ("", [Waypoint((0.0,), "release")], "name"),
        ("empty", [], "waypoint"),
    ],
)
def test_invalid_programs_are_refused(tmp_path, name, waypoints, message):
    store = Store(tmp_path / "db.sqlite3")
    with pytest.raises(ValueError, match=message):
        store.save_program(name, waypoints)
    assert store.list_programs() == []


@pytest.mark.parametrize(("joints", "gripper"), [((math.nan,), "grasp"), ((0.0,), "squeeze"), ((), "grasp")])
def test_bad_waypoints_are_refused(joints, gripper):
    with pytest.raises(ValueError):
        Waypoint(joints, gripper)


def test_latest_calibration_and_job_results(tmp_path):
    store = Store(tmp_path / "db.sqlite3")
    assert store.latest_calibration() is None
    store.save_calibration({"n": 1})
    store.save_calibration({"n": 2})
    assert Store(tmp_path / "db.sqlite3").latest_calibration() == {"n": 2}
    job = {"id": "j1", "name": "grab", "state": "running", "message": "", "started_s": 10.0, "finished_s": None, "result": None}
    store.record_job(job)
    store.record_job({**job, "state": "succeeded", "finished_s": 12.0, "result": {"holding": True}})
    results = store.job_results()
    assert len(results) == 1 and results[0]["state"] == "succeeded" and results[0]["result"] == {"holding": True}
