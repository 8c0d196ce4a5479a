"""Teach, programs and repeat over real HTTP (issue 9): undo and the on-disk draft, edits checked against
the limits, JSON/CSV export and import, and the bad inputs that must be refused with nothing moved and
nothing stored changed; repeat's pause, resume and speed override on the real-time simulation."""

from __future__ import annotations

import json
import sqlite3

import httpx
import numpy as np
import pytest

import live
from server.app import create_app

TOKEN = "programs-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
STILL_TOL_RAD = 5e-3
POSE_A = [0.3, 0.1, 0.2, 0.4, 0.0]
POSE_B = [-0.3, 0.0, 0.3, 0.5, 0.2]
POSE_C = [0.0, -0.2, 0.1, 0.6, 0.0]


@pytest.fixture(scope="module")
def cell():
    cell = live.start_cell(seed=3, time_scale=live.FAST_TIME_SCALE)
    yield cell
    cell.close()


@pytest.fixture(scope="module")
def db_path(tmp_path_factory):
    return tmp_path_factory.mktemp("programs") / "station.sqlite3"


@pytest.fixture(scope="module")
def url(cell, db_path):
    app = create_app(station_factory=lambda: live.StationOnCell(cell, db_path), token=TOKEN)
    with live.serve(app) as base_url:
        yield base_url


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=60.0) as client:
        _idle(client)
        yield client
        _idle(client)


def _idle(client) -> None:
    if client.get("/api/status").json()["state"] != "idle":
        client.post("/api/estop", headers=AUTH)
        client.post("/api/reset", headers=AUTH)
    live.wait_for(lambda: not client.get("/api/status").json()["moving"], 10)


def _error(response, status_code: int, code: str) -> str:
    assert response.status_code == status_code, response.text
    body = response.json()["error"]
    assert body["code"] == code, body
    return body["message"]


def _move(client, q) -> None:
    response = client.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": q, "moving_time_s": 0.6}, headers=AUTH)
    assert response.status_code in (200, 202), response.text
    live.wait_for(lambda: not client.get("/api/status").json()["moving"], 10)


def _teach(client, name: str, poses, grippers=None) -> dict:
    assert client.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).status_code == 200
    for index, q in enumerate(poses):
        _move(client, q)
        gripper = (grippers or ["release"] * len(poses))[index]
        client.post("/api/gripper", params={"wait": "true"}, json={"action": gripper}, headers=AUTH)
        assert client.post("/api/teach/record", headers=AUTH).status_code == 200
    response = client.post("/api/teach/stop", json={"name": name}, headers=AUTH)
    assert response.status_code == 200, response.text
    client.post("/api/gripper", params={"wait": "true"}, json={"action": "release"}, headers=AUTH)
    return response.json()


def _stored(client) -> list:
    return client.get("/api/programs").json()["data"]


def test_record_undo_and_the_draft_on_disk(http):
    assert http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).json()["detail"] == "teaching: 0 waypoints"
    _move(http, POSE_A)
    first = http.post("/api/teach/record", json={"dwell_s": 0.5}, headers=AUTH).json()
    assert first["count"] == 1 and first["dwell_s"] == 0.5 and np.allclose(first["joints_rad"], POSE_A, atol=0.02)
    _move(http, POSE_B)
    assert http.post("/api/teach/record", headers=AUTH).json()["count"] == 2
    draft = http.get("/api/teach/draft").json()
    assert draft["count"] == 2 and np.allclose(draft["waypoints"][1]["joints_rad"], POSE_B, atol=0.02)
    undone = http.post("/api/teach/undo", headers=AUTH).json()
    assert undone["count"] == 1 and np.allclose(undone["removed"]["joints_rad"], POSE_B, atol=0.02)
    assert http.get("/api/teach/draft").json()["count"] == 1
    program = http.post("/api/teach/stop", json={"name": "undo demo"}, headers=AUTH).json()
    assert len(program["waypoints"]) == 1 and program["waypoints"][0]["dwell_s"] == 0.5
    assert http.get("/api/teach/draft").json()["count"] == 0  # saved and emptied in one go
    _error(http.post("/api/teach/undo", headers=AUTH), 409, "wrong_state")  # not teaching


def test_trajectory_mode_records_the_motion_at_the_chosen_rate(http, cell):
    http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH)
    _move(http, [0.0, 0.0, 0.0, 0.0, 0.0])
    started = http.post("/api/teach/continuous", json={"rate_hz": 10}, headers=AUTH)
    assert started.status_code == 200 and started.json()["recording"], started.text
    _error(http.post("/api/teach/continuous", json={"rate_hz": 50}, headers=AUTH), 422, "invalid")
    response = http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": [0.8, 0.0, 0.0, 0.0, 0.0], "moving_time_s": 1.5}, headers=AUTH)
    assert response.status_code in (200, 202)
    stopped = http.post("/api/teach/continuous/stop", headers=AUTH).json()
    draft = http.get("/api/teach/draft").json()["waypoints"]
    assert stopped["recording"] is False and stopped["count"] == len(draft)
    waist = [w["joints_rad"][0] for w in draft]
    assert 4 <= len(draft) <= 20, waist  # ~10 Hz over the 1.5 s move (fewer on a loaded machine), none while still
    assert all(b > a for a, b in zip(waist, waist[1:])) and waist[-1] > 0.7  # along the motion, in order
    assert all(w["moving_time_s"] >= 0.099 for w in draft[1:])  # the recorded pace: at least one period apart
    count = len(draft)
    http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": [0.6, 0.0, 0.0, 0.0, 0.0], "moving_time_s": 0.5}, headers=AUTH)
    live.wait_sim(cell, 0.3)
    assert http.get("/api/teach/draft").json()["count"] == count  # stopped: the move after it was not recorded
    program = http.post("/api/teach/stop", json={"name": "recorded"}, headers=AUTH).json()
    assert len(program["waypoints"]) == count


def test_stopping_the_recorder_keeps_where_the_motion_ended(http, cell):
    """A recorder tick that comes late (a loaded machine; here a slow rate) must not cut the motion's end off
    the program: stopping records where the arm is, if it moved since the last record (the suite under load
    once ended a recorded 0 -> 0.8 rad move at 0.657 rad)."""
    http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH)
    _move(http, [0.0, 0.0, 0.0, 0.0, 0.0])
    assert http.post("/api/teach/continuous", json={"rate_hz": 0.5}, headers=AUTH).status_code == 200  # a tick every 2 s
    response = http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": [0.8, 0.0, 0.0, 0.0, 0.0], "moving_time_s": 1.0}, headers=AUTH)
    assert response.status_code in (200, 202)
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 10)
    stopped = http.post("/api/teach/continuous/stop", headers=AUTH).json()
    draft = http.get("/api/teach/draft").json()["waypoints"]
    assert stopped["count"] == len(draft) >= 1
    assert abs(draft[-1]["joints_rad"][0] - 0.8) < 0.02, [w["joints_rad"][0] for w in draft]
    http.post("/api/teach/stop", json={"name": "ends where it ended"}, headers=AUTH)


def test_teach_start_resumes_an_unsaved_draft_unless_discarded(http):
    http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH)
    _move(http, POSE_C)
    http.post("/api/teach/record", headers=AUTH)
    http.post("/api/estop", headers=AUTH)  # leave teach without saving
    http.post("/api/reset", headers=AUTH)
    status = http.post("/api/teach/start", headers=AUTH).json()
    assert status["state"] == "teach" and "1 waypoints (draft resumed)" in status["detail"]
    assert http.post("/api/teach/record", headers=AUTH).json()["count"] == 2
    http.post("/api/estop", headers=AUTH)
    http.post("/api/reset", headers=AUTH)
    assert http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).json()["detail"] == "teaching: 0 waypoints"
    assert http.get("/api/teach/draft").json()["count"] == 0


def test_teach_can_be_left_without_saving_and_without_an_estop(http):
    """Issue 18 item 8: with an empty draft, teach/stop has nothing to save (422) and teach was left only by
    e-stop and reset. POST /api/teach/exit leaves teach for idle without saving; the draft stays on disk
    (the next teach/start resumes it), nothing moves."""
    assert http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH).status_code == 200
    _error(http.post("/api/teach/stop", json={"name": "empty"}, headers=AUTH), 422, "invalid")
    response = http.post("/api/teach/exit", headers=AUTH)
    assert response.status_code == 200, response.text
    assert response.json()["state"] == "idle" and not response.json()["moving"]
    assert http.post("/api/teach/start", headers=AUTH).status_code == 200
    _move(http, POSE_C)
    assert http.post("/api/teach/record", headers=AUTH).json()["count"] == 1
    stored = _stored(http)
    assert http.post("/api/teach/exit", headers=AUTH).json()["state"] == "idle"
    assert _stored(http) == stored and http.get("/api/teach/draft").json()["count"] == 1  # kept, not saved
    assert "1 waypoints (draft resumed)" in http.post("/api/teach/start", headers=AUTH).json()["detail"]
    assert http.post("/api/teach/exit", headers=AUTH).json()["state"] == "idle"
    _error(http.post("/api/teach/exit", headers=AUTH), 409, "wrong_state")  # not teaching


def test_edit_rename_reorder_insert_a_gripper_step_and_duplicate(http):
    program = _teach(http, "edit me", [POSE_A, POSE_B])
    pid = program["id"]
    waypoints = program["waypoints"]
    step = {**waypoints[0], "gripper": "grasp"}  # a gripper step: same pose, the other command
    new = [waypoints[1], waypoints[0], step]
    new[0] = {**new[0], "joints_rad": [*new[0]["joints_rad"][:4], 0.5], "moving_time_s": 2.0}  # edit a value
    edited = http.patch(f"/api/programs/{pid}", json={"name": "edited", "waypoints": new}, headers=AUTH)
    assert edited.status_code == 200, edited.text
    stored = http.get(f"/api/programs/{pid}").json()
    assert stored["name"] == "edited" and [w["gripper"] for w in stored["waypoints"]] == ["release", "release", "grasp"]
    assert stored["waypoints"][0]["joints_rad"][4] == 0.5 and stored["waypoints"][0]["moving_time_s"] == 2.0
    copy = http.post(f"/api/programs/{pid}/duplicate", headers=AUTH)
    assert copy.status_code == 201 and copy.json()["name"] == "edited (copy)" and copy.json()["waypoints"] == stored["waypoints"]
    assert http.patch(f"/api/programs/{pid}", json={"name": "renamed"}, headers=AUTH).json()["waypoints"] == stored["waypoints"]


def test_export_and_import_round_trip_json_and_csv(http):
    program = _teach(http, "round trip", [POSE_A, POSE_B, POSE_C], ["release", "grasp", "release"])
    pid = program["id"]
    as_json = http.get(f"/api/programs/{pid}/export", params={"format": "json"})
    assert as_json.status_code == 200 and as_json.headers["content-type"].startswith("application/json")
    imported = http.post("/api/programs/import", json={"format": "json", "content": as_json.text}, headers=AUTH)
    assert imported.status_code == 201, imported.text
    assert imported.json()["name"] == "round trip" and imported.json()["waypoints"] == program["waypoints"]
    as_csv = http.get(f"/api/programs/{pid}/export", params={"format": "csv"})
    assert as_csv.headers["content-type"].startswith("text/csv")
    lines = as_csv.text.strip().splitlines()
    assert lines[0] == "t_s,q1,q2,q3,q4,q5,gripper" and len(lines) == 4
    times = [float(line.split(",")[0]) for line in lines[1:]]
    assert times[0] == 0.0 and times[1] > 0.2 and times[2] > times[1]  # when each waypoint is reached
    back = http.post("/api/programs/import", json={"format": "csv", "content": as_csv.text, "name": "from csv"}, headers=AUTH).json()
    for got, want in zip(back["waypoints"], program["waypoints"]):
        assert np.allclose(got["joints_rad"], want["joints_rad"], atol=1e-8) and got["gripper"] == want["gripper"]


BAD_CSV = [
    ("t_s,q1,q2,q3,q4,q5\n0,0,0,0,0,0\n", "line 1"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n0.5,0,abc,0,0,0,grasp\n", "line 3: q2 = 'abc' is not a number"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n1,0,0,0,0,0,squeeze\n", "line 3: gripper"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n1,0,0,0,0\n", "line 3: 5 values"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n2,0.1,0,0,0,0,release\n1,0.2,0,0,0,0,release\n", "line 4: t_s"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n", "no waypoints"),
    ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,3.0,0,0,0,release\n", "shoulder"),  # outside the joint limits
]


@pytest.mark.parametrize(("content", "reason"), BAD_CSV)
def test_a_malformed_csv_import_names_the_line_and_stores_nothing(http, content, reason):
    before = _stored(http)
    message = _error(http.post("/api/programs/import", json={"format": "csv", "content": content}, headers=AUTH), 422, "invalid")
    assert reason in message
    assert _stored(http) == before


@pytest.mark.parametrize(
    ("content", "reason"),
    [
        ('{"waypoints": [{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release"},\n {"joints_rad": [0, 0], "gripper": "grasp"}]}', "waypoint 2: 2 joint values"),
        ('{"waypoints": [\n{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release"},,]}', "line 2"),
        ('{"waypoints": []}', "no waypoints"),
        ('{"waypoints": [{"joints_rad": [0, 0, 0, 0, 9], "gripper": "release"}]}', "wrist_rotate"),
    ],
)
def test_a_malformed_json_import_is_refused_and_stores_nothing(http, content, reason):
    before = _stored(http)
    message = _error(http.post("/api/programs/import", json={"format": "json", "content": content}, headers=AUTH), 422, "invalid")
    assert reason in message
    assert _stored(http) == before


def test_bad_edits_and_repeats_are_refused_nothing_moves_nothing_changes(http):
    program = _teach(http, "bad input", [POSE_A, POSE_B])
    pid = program["id"]
    before, joints = _stored(http), np.array(http.get("/api/status").json()["joints_rad"])
    outside = [{"joints_rad": [0.0, 2.5, 0.0, 0.0, 0.0], "gripper": "release"}]  # shoulder beyond 113°
    assert "shoulder" in _error(http.patch(f"/api/programs/{pid}", json={"waypoints": outside}, headers=AUTH), 422, "invalid")
    below = [{"joints_rad": [0.0, 1.9, 1.6, 0.0, 0.0], "gripper": "release"}]  # in the limits, through the table
    assert "waypoint 1" in _error(http.patch(f"/api/programs/{pid}", json={"waypoints": below}, headers=AUTH), 422, "unsafe")
    _error(http.patch(f"/api/programs/{pid}", json={"waypoints": []}, headers=AUTH), 422, "invalid")  # empty program
    _error(http.patch("/api/programs/987654", json={"name": "x"}, headers=AUTH), 404, "not_found")
    _error(http.post("/api/programs/987654/repeat", json={"cycles": 1}, headers=AUTH), 404, "not_found")
    for speed in (5, 9.99, 100.5, 0):
        _error(http.post(f"/api/programs/{pid}/repeat", json={"speed_percent": speed}, headers=AUTH), 422, "invalid")
    _error(http.post(f"/api/programs/{pid}/repeat", json={"cycles": 0}, headers=AUTH), 422, "invalid")
    _error(http.post("/api/jobs/pause", headers=AUTH), 409, "wrong_state")  # nothing to pause
    _error(http.patch("/api/jobs/current", json={"speed_percent": 50}, headers=AUTH), 409, "wrong_state")
    http.post("/api/teach/start", json={"discard_draft": True}, headers=AUTH)  # repeat while not idle
    _error(http.post(f"/api/programs/{pid}/repeat", json={"cycles": 1}, headers=AUTH), 409, "wrong_state")
    _error(http.post("/api/teach/stop", json={"name": "empty"}, headers=AUTH), 422, "invalid")  # no waypoints
    status = http.get("/api/status").json()
    assert status["state"] == "teach" and not status["moving"]
    assert float(np.max(np.abs(np.subtract(status["joints_rad"], joints)))) < STILL_TOL_RAD
    assert _stored(http) == before


def test_a_waypoint_below_the_table_in_a_stored_program_refuses_the_repeat(http, db_path):
    program = _teach(http, "table", [POSE_A, POSE_B])  # then made bad behind the API's back (an old file, a hand edit)
    joints = np.array(http.get("/api/status").json()["joints_rad"])
    bad = json.dumps([{"joints_rad": POSE_A, "gripper": "release"}, {"joints_rad": [0.0, 1.9, 1.6, 0.0, 0.0], "gripper": "release"}])
    connection = sqlite3.connect(db_path)
    with connection:
        connection.execute("UPDATE programs SET waypoints_json = ? WHERE id = ?", (bad, program["id"]))
    connection.close()
    message = _error(http.post(f"/api/programs/{program['id']}/repeat", json={"cycles": 1}, headers=AUTH), 422, "unsafe")
    assert "waypoint 2" in message and "below the board" in message
    status = http.get("/api/status").json()
    assert status["state"] == "idle" and not status["moving"]
    assert float(np.max(np.abs(np.subtract(status["joints_rad"], joints)))) < STILL_TOL_RAD


def test_repeat_pauses_resumes_changes_speed_and_goes_home(http, cell):
    program = _teach(http, "pause me", [POSE_A, POSE_B, POSE_C])
    job = http.post(f"/api/programs/{program['id']}/repeat", json={"cycles": 2, "speed_percent": 60}, headers=AUTH)
    assert job.status_code == 202, job.text
    live.wait_for(lambda: ((http.get("/api/jobs/current").json()["job"] or {}).get("extra") or {}).get("repeat", {}).get("phase") == "cycle", 30)
    assert http.post("/api/jobs/pause", headers=AUTH).status_code == 200
    live.wait_for(lambda: http.get("/api/jobs/current").json()["job"]["extra"]["repeat"]["paused"], 10)
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 10)
    held = np.array(http.get("/api/status").json()["joints_rad"])
    status = http.get("/api/status").json()
    assert status["state"] == "repeat" and status["job"]["state"] == "running"
    live.wait_sim(cell, 0.3)
    assert float(np.max(np.abs(np.subtract(http.get("/api/status").json()["joints_rad"], held)))) < STILL_TOL_RAD  # holds
    changed = http.patch("/api/jobs/current", json={"speed_percent": 100}, headers=AUTH)
    assert changed.status_code == 200 and changed.json()["job"]["extra"]["repeat"]["speed_percent"] in (60, 100)
    assert http.post("/api/jobs/resume", headers=AUTH).status_code == 200
    live.wait_for(lambda: http.get("/api/status").json()["moving"], 10)
    final = live.wait_for(lambda: (j := http.get("/api/jobs/current").json()["job"])["state"] != "running" and j, 120)
    assert final["state"] == "succeeded", final
    progress = final["extra"]["repeat"]
    assert progress["cycle"] == 2 and progress["speed_percent"] == 100 and progress["phase"] == "home"
    assert np.allclose(http.get("/api/status").json()["joints_rad"], 0.0, atol=0.02)  # home at the end
    trace = http.get("/api/jobs/current/trace", params={"format": "csv"})
    assert trace.status_code == 200 and trace.text.startswith("t_s,waist_cmd_rad")
    rows = np.array([[float(v) for v in line.split(",")] for line in trace.text.splitlines()[1:]])
    # A cycle of a few seconds sampled as the job waits (up to 50 Hz; fewer on a machine at load 20): rows of time,
    # 5 commanded and 5 measured joints, in time order, over the cycle.
    assert rows.shape[0] >= 5 and rows.shape[1] == 11 and np.isfinite(rows).all(), trace.text[:500]
    assert np.all(np.diff(rows[:, 0]) > 0) and rows[-1, 0] - rows[0, 0] > 0.5, rows[:, 0]

