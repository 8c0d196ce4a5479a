"""Programs belong to an arm and a workcell (issue 21, broken item 1): one database file used by the RX200
station and then the UR3 station. Before, the UR3 station's GET /api/programs answered 422 ("q: expected
shape (6,) … got (5,)") because the RX200's program was in the file. Now each station lists its own, counts
the others, refuses another arm's program by id (nothing moves), and a damaged row never hides the rest.
Real HTTP, real-time simulations of both workcells, one after the other on the same file."""

from __future__ import annotations

import sqlite3

import httpx
import numpy as np
import pytest

import live
from armlab.station.config import StationConfig
from armlab.station.factory import make_sim_station
from armlab.store_schema import MIGRATIONS
from server.app import create_app

TOKEN = "per-arm-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


def _station_url(workcell: str, db_path):
    app = create_app(station_factory=lambda: make_sim_station(StationConfig(workcell=workcell), db_path), token=TOKEN)
    return live.serve(app)


def _teach_here(client: httpx.Client, name: str) -> dict:
    """Teach a one-waypoint program at the arm's current pose over HTTP."""
    assert client.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).status_code == 200
    recorded = client.post("/api/teach/record", headers=AUTH)
    assert recorded.status_code == 200, recorded.text
    saved = client.post("/api/teach/stop", json={"name": name}, headers=AUTH)
    assert saved.status_code == 200, saved.text
    return saved.json()


@pytest.fixture(scope="module")
def shared_db(tmp_path_factory):
    return tmp_path_factory.mktemp("per_arm") / "shared.sqlite3"


def test_each_station_lists_its_own_programs_and_counts_the_other_arms(shared_db):
    with _station_url("rx200_armlab", shared_db) as url, httpx.Client(base_url=url, timeout=60.0) as http:
        rx_program = _teach_here(http, "rx200 pose")
        assert len(rx_program["waypoints"][0]["joints_rad"]) == 5
        # a teach draft left unsaved by the RX200 station, in the same file
        assert http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).status_code == 200
        assert http.post("/api/teach/record", headers=AUTH).status_code == 200

    with _station_url("ur3_suction", shared_db) as url, httpx.Client(base_url=url, timeout=60.0) as http:
        listed = http.get("/api/programs")
        assert listed.status_code == 200, listed.text  # was 422: the RX200's five joints through the UR3's FK
        body = listed.json()
        assert body["data"] == [] and body["count"] == 0 and body["skipped"] == []
        assert body["others_count"] == 1 and body["others"] == [{"arm": "rx200", "workcell": "rx200_armlab", "count": 1}]
        assert http.get("/api/teach/draft").json()["count"] == 0  # the RX200's draft is not resumed on the UR3

        ur_program = _teach_here(http, "ur3 pose")
        assert ur_program["arm"] == "ur3" and ur_program["workcell"] == "ur3_suction" and len(ur_program["waypoints"][0]["joints_rad"]) == 6
        body = http.get("/api/programs").json()
        assert [p["id"] for p in body["data"]] == [ur_program["id"]] and body["others_count"] == 1

        refused = http.get(f"/api/programs/{rx_program['id']}")
        assert refused.status_code == 409 and "rx200" in refused.json()["error"]["message"], refused.text
        q_before = np.asarray(http.get("/api/status").json()["joints_rad"])
        repeat = http.post(f"/api/programs/{rx_program['id']}/repeat", json={"cycles": 1}, headers=AUTH)
        assert repeat.status_code == 409 and "rx200" in repeat.json()["error"]["message"], repeat.text
        for edit in (http.delete(f"/api/programs/{rx_program['id']}", headers=AUTH),
                     http.post(f"/api/programs/{rx_program['id']}/duplicate", headers=AUTH),
                     http.get(f"/api/programs/{rx_program['id']}/export")):
            assert edit.status_code == 409, edit.text
        status = http.get("/api/status").json()
        assert status["job"] is None or status["job"]["name"] != "repeat"
        assert np.allclose(status["joints_rad"], q_before, atol=2e-3)  # nothing moved

    with _station_url("rx200_armlab", shared_db) as url, httpx.Client(base_url=url, timeout=60.0) as http:
        body = http.get("/api/programs").json()
        assert [(p["id"], p["arm"], p["workcell"]) for p in body["data"]] == [(rx_program["id"], "rx200", "rx200_armlab")]
        assert body["others"] == [{"arm": "ur3", "workcell": "ur3_suction", "count": 1}]
        assert http.get("/api/teach/draft").json()["count"] == 1  # and its draft too


def test_rows_from_before_programs_had_an_arm_go_to_the_arm_with_as_many_joints(tmp_path):
    """A file from before schema 5 (no arm column) with a five- and a six-joint program and a damaged row:
    the RX200 lists the five-joint one, the UR3 the six-joint one, each counts the other; the damaged row is
    named in `skipped`, never a failure of the list."""
    db_path = tmp_path / "old.sqlite3"
    connection = sqlite3.connect(db_path)
    connection.executescript("".join(MIGRATIONS[:4]) + "PRAGMA user_version = 4;")  # the file a schema 4 station made
    with connection:
        for name, joints in (("five", "[0.0, 0.0, 0.0, 0.0, 0.0]"), ("six", "[0.0, -1.57, 1.2, -1.2, -1.57, 0.0]")):
            connection.execute("INSERT INTO programs (name, created_s, waypoints_json, updated_s) VALUES (?, 1.0, ?, 1.0)",
                               (name, f'[{{"joints_rad": {joints}, "gripper": "release"}}]'))
        connection.execute("INSERT INTO programs (name, created_s, waypoints_json, updated_s) VALUES ('broken', 1.0, '[{', 1.0)")
    connection.close()
    for workcell, mine, other_arm in (("rx200_armlab", "five", None), ("ur3_suction", "six", None)):
        with _station_url(workcell, db_path) as url:
            body = httpx.get(url + "/api/programs", timeout=60.0).json()
            assert [p["name"] for p in body["data"]] == [mine], body
            assert body["others_count"] == 1 and body["others"][0]["arm"] is other_arm
            assert len(body["skipped"]) == 1 and "program 3" in body["skipped"][0]
