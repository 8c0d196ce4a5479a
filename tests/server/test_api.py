"""The REST API over real HTTP: a uvicorn server on a free 127.0.0.1 port, httpx as the client,
the station on the real-time simulation."""

from __future__ import annotations

import time

import cv2
import httpx
import numpy as np
import pytest

import live
from server.app import create_app

TOKEN = "test-token-123"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
# A halted arm settles by a few mrad under gravity; a move that kept going would travel ~0.1 rad or more.
HALT_TOL_RAD = 5e-3


@pytest.fixture(scope="module")
def cell():
    cell = live.start_cell(seed=5, time_scale=live.FAST_TIME_SCALE)
    yield cell
    cell.close()


@pytest.fixture(scope="module")
def db_path(tmp_path_factory):
    return tmp_path_factory.mktemp("api") / "station.sqlite3"


@pytest.fixture(scope="module")
def url(cell, db_path):
    app = create_app(station_factory=lambda: live.StationOnCell(cell, db_path), token=TOKEN)
    with live.serve(app) as base_url:
        yield base_url


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=30.0) as client:
        _idle(client)
        yield client
        _idle(client)


def _idle(client: httpx.Client) -> None:
    status = client.get("/api/status").json()
    if status["state"] != "idle":
        client.post("/api/estop", headers=AUTH)
        client.post("/api/reset", headers=AUTH)
    live.wait_for(lambda: not client.get("/api/status").json()["moving"], 10)


def _joints(client) -> np.ndarray:
    return np.array(client.get("/api/status").json()["joints_rad"])


def _error(response, status_code: int, code: str) -> dict:
    assert response.status_code == status_code, response.text
    body = response.json()["error"]
    assert body["code"] == code and isinstance(body["message"], str) and len(body["message"]) > 10
    return body


def test_health_status_and_openapi(http):
    assert http.get("/api/health").json()["status"] == "ok"
    status = http.get("/api/status").json()
    assert status["state"] == "idle" and status["backend"] == "sim"
    assert status["joint_names"] == ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"]
    assert len(status["joints_rad"]) == 5 and len(status["gripper_pose"]["position_m"]) == 3
    assert status["joint_limits_rad"][1] == pytest.approx([-1.885, 1.972], abs=1e-3)  # shoulder -108..113 deg
    assert set(status["gripper"]) == {"width_m", "holding", "command"}
    assert "estop" in status["allowed_commands"] and "reset" not in status["allowed_commands"]
    assert abs(status["time_s"] - time.time()) < 5
    assert http.get("/docs").status_code == 200
    paths = http.get("/openapi.json").json()["paths"]
    for path in ("/api/status", "/api/arm/joints", "/api/grab", "/api/calibrate", "/api/programs/{program_id}/repeat"):
        assert path in paths


def test_mutating_calls_need_the_token_and_move_nothing_without_it(http, cell):
    q_before = _joints(http)
    # (e-stop needs no token: any page the station serves may stop the arm; tests/server/test_estop_route.py)
    for path, body in (("/api/arm/joints", {"q_rad": [0.5, 0, 0, 0, 0]}), ("/api/calibrate", None), ("/api/arm/home", None)):
        _error(http.post(path, json=body), 401, "unauthorized")
        _error(http.post(path, json=body, headers={"Authorization": "Bearer wrong"}), 401, "unauthorized")
    live.wait_sim(cell, 0.2)
    assert np.allclose(_joints(http), q_before, atol=2e-3)
    assert http.get("/api/status").json()["state"] == "idle"


def test_joint_move_with_wait_reaches_the_goal(http):
    goal = [0.3, 0.1, -0.1, 0.2, 0.0]
    response = http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": goal, "moving_time_s": 0.8}, headers=AUTH)
    assert response.status_code == 200, response.text
    assert np.allclose(_joints(http), goal, atol=0.02)
    assert http.get("/api/status").json()["controller"] == "api"


@pytest.mark.parametrize(
    ("body", "fragment"),
    [
        ('{"q_rad": [0, NaN, 0, 0, 0]}', "q_rad"),
        ('{"q_rad": [0, 0, 0]}', "5 values"),
        ('{"q_rad": [0, 3.0, 0, 0, 0]}', "shoulder"),
        ('{"q_rad": [0, 0, 0, 0, 0], "speed": 3}', "speed"),
        ('{"q_rad": [0, 0, 0, 0, 0], "moving_time_s": -2}', "moving_time_s"),
        ('{"q_rad": [0, 0, 0', "JSON"),
        ('"just a string"', "body"),
    ],
)
def test_bad_joint_input_is_422_and_nothing_moves(http, cell, body, fragment):
    q_before = _joints(http)
    response = http.post("/api/arm/joints", content=body, headers={**AUTH, "Content-Type": "application/json"})
    error = _error(response, 422, "invalid")
    assert fragment in error["message"]
    live.wait_sim(cell, 0.15)
    assert np.allclose(_joints(http), q_before, atol=2e-3)


def test_unreachable_pose_is_422_unreachable(http, cell):
    q_before = _joints(http)
    error = _error(http.post("/api/arm/pose", json={"position_m": [0.0, 0.9, 0.1]}, headers=AUTH), 422, "unreachable")
    assert "reach" in error["message"] or "limit" in error["message"]
    _error(http.post("/api/arm/pose", json={"position_m": [0.0, 0.3]}, headers=AUTH), 422, "invalid")
    live.wait_sim(cell, 0.15)
    assert np.allclose(_joints(http), q_before, atol=2e-3)


def test_pose_move_puts_the_gripper_point_there(http):
    target = [0.05, 0.25, 0.12]
    response = http.post("/api/arm/pose", params={"wait": "true"}, json={"position_m": target, "pitch_rad": 1.2, "moving_time_s": 1.0}, headers=AUTH)
    assert response.status_code == 200, response.text
    pose = http.get("/api/status").json()["gripper_pose"]
    assert np.allclose(pose["position_m"], target, atol=0.004)
    assert pose["pitch_rad"] == pytest.approx(1.2, abs=0.02)


def test_estop_latches_with_409_naming_allowed_commands_and_reset_does_not_move(http, cell):
    http.post("/api/arm/joints", json={"q_rad": [0.8, 0.2, 0.1, 0.3, 0.0], "moving_time_s": 2.0}, headers=AUTH)
    live.wait_for(lambda: http.get("/api/status").json()["moving"], 5)
    status = http.post("/api/estop", headers=AUTH).json()
    assert status["state"] == "estop" and status["allowed_commands"] == ["estop", "reset"]
    live.wait_sim(cell, 0.05)  # the arm's momentum
    q_halted = _joints(http)
    error = _error(http.post("/api/arm/home", headers=AUTH), 409, "wrong_state")
    assert error["allowed"] == ["estop", "reset"] and "home" in error["message"]
    _error(http.post("/api/grab", json={"position_m": [0, 0.25, 0.02]}, headers=AUTH), 409, "wrong_state")
    live.wait_sim(cell, 0.3)
    assert np.allclose(_joints(http), q_halted, atol=HALT_TOL_RAD)
    assert http.post("/api/reset", headers=AUTH).json()["state"] == "idle"
    live.wait_sim(cell, 0.3)
    assert np.allclose(_joints(http), q_halted, atol=HALT_TOL_RAD)
    error = _error(http.post("/api/reset", headers=AUTH), 409, "wrong_state")
    assert "reset" not in error["allowed"] and "estop" in error["allowed"]


def test_estop_releases_a_request_waiting_for_its_move(http, url):
    import threading

    result = {}

    goal = [-0.8, 0.2, 0.1, 0.3, 0.0]

    def long_move():
        with httpx.Client(base_url=url, timeout=30) as other:
            body = {"q_rad": goal, "moving_time_s": 4.0}
            result["response"] = other.post("/api/arm/joints", params={"wait": "true"}, json=body, headers=AUTH)

    waiter = threading.Thread(target=long_move)
    waiter.start()
    live.wait_for(lambda: http.get("/api/status").json()["moving"], 5)
    assert http.post("/api/estop", headers=AUTH).json()["state"] == "estop"
    waiter.join(10)
    assert not waiter.is_alive(), "the waiting request outlived the e-stop"
    answer = result["response"].json()
    assert result["response"].status_code == 200 and answer["state"] == "estop"
    # It was released by the e-stop, not by the end of the 4 s move: the arm is still far from the goal.
    assert np.abs(np.array(answer["joints_rad"]) - goal).max() > 0.1


def test_gripper_and_torque(http):
    status = http.post("/api/gripper", json={"action": "grasp"}, headers=AUTH).json()
    assert status["gripper"]["command"] == "grasp" and status["gripper"]["width_m"] < 0.03
    status = http.post("/api/gripper", json={"action": "release"}, headers=AUTH).json()
    assert status["gripper"]["command"] == "release" and status["gripper"]["width_m"] > 0.05
    _error(http.post("/api/gripper", json={"action": "squeeze"}, headers=AUTH), 422, "invalid")
    assert http.post("/api/arm/torque", json={"enabled": True}, headers=AUTH).status_code == 200
    assert http.get("/api/status").json()["controller"] == "api"
    # Torque off while idle would let the arm fall: 409 unless confirmed, and nothing changes.
    q_before = _joints(http)
    _error(http.post("/api/arm/torque", json={"enabled": False}, headers=AUTH), 409, "needs_confirmation")
    assert not http.get("/api/status").json()["moving"]
    assert np.allclose(_joints(http), q_before, atol=2e-3)
    # A page (browsers add Sec-Fetch-Mode to fetch()) is another controller: refused until it takes control.
    browser = {**AUTH, "Sec-Fetch-Mode": "cors"}
    error = _error(http.post("/api/gripper", json={"action": "release"}, headers=browser), 409, "not_controller")
    assert "'api'" in error["message"]
    assert http.post("/api/control/take", headers=browser).json()["controller"] == "ui"
    assert http.post("/api/gripper", json={"action": "release"}, headers=browser).json()["controller"] == "ui"
    assert http.post("/api/control/release", headers=browser).json()["controller"] is None


def test_pixel_to_world_before_calibration_is_409(http):
    assert not http.get("/api/status").json()["calibrated"]  # runs before the calibration test below
    _error(http.post("/api/pixel-to-world", json={"u": 640, "v": 360}), 409, "not_calibrated")


def test_calibrate_detect_frames_and_click_grab_drop(http, cell):
    scene = {"objects": [{"id": "g", "type": "block", "color": "green", "size": "small", "position_m": [-0.05, 0.28, 0.0125], "yaw_rad": 0.2}]}
    assert http.post("/api/sim/scene", json=scene, headers=AUTH).status_code == 200
    _error(http.post("/api/sim/scene", json={"objects": scene["objects"], "event": "pick_sort"}, headers=AUTH), 422, "invalid")
    response = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH)
    assert response.status_code == 200 and response.json()["job"]["state"] == "succeeded", response.text
    calibration = http.get("/api/calibration").json()
    assert calibration["calibrated"] and calibration["reprojection_error_px"] < 1.0
    truth = http.get("/api/sim/truth").json()
    camera_true = np.array(truth["camera"]["T_world_camera"])[:3, 3]
    assert np.linalg.norm(np.array(calibration["camera_position_m"]) - camera_true) < 0.01
    assert len(calibration["grid_points_px"]) > 100 and {t["id"] for t in calibration["tags"]} - {10} == {1, 2, 3, 4}  # 10: the gripper's tag
    # The depth camera against the tags' plane, measured from the board in depth and reported (issue 17).
    assert isinstance(calibration["depth_offset_m"], float) and abs(calibration["depth_offset_m"]) < 0.03
    assert 0.0 <= calibration["depth_tilt_deg"] < 3.0 and "the tags' plane, tilted" in calibration["depth_model"]
    detections = live.wait_for(lambda: http.get("/api/detections").json()["data"], 10)
    assert detections[0]["color"] == "green" and detections[0]["size"] == "small"
    assert np.allclose(detections[0]["position_m"][:2], [-0.05, 0.28], atol=0.004)
    # pixel → world at the block's top
    u, v = detections[0]["center_px"]
    point = http.post("/api/pixel-to-world", json={"u": u, "v": v}).json()
    assert point["on"] == "depth" and np.allclose(point["position_m"], [-0.05, 0.28, 0.025], atol=0.006)
    _error(http.post("/api/pixel-to-world", json={"u": 5000, "v": 10}), 422, "invalid")
    # snapshots with overlays
    for view in ("color", "depth", "topdown"):
        response = http.get("/api/frame.jpg", params={"view": view, "layers": "tags,detections,grid"})
        assert response.status_code == 200 and response.headers["content-type"] == "image/jpeg"
        image = cv2.imdecode(np.frombuffer(response.content, np.uint8), cv2.IMREAD_COLOR)
        assert image is not None and image.shape[2] == 3
        assert abs(float(response.headers["X-Capture-Time-S"]) - time.time()) < 5
    _error(http.get("/api/frame.jpg", params={"view": "xray"}), 422, "invalid")
    # click-grab by pixel: 202 + job at once, then the job runs
    response = http.post("/api/grab", json={"u": u, "v": v}, headers=AUTH)
    assert response.status_code == 202, response.text
    job = response.json()["job"]
    assert job["state"] == "running" and job["name"] == "grab"
    assert http.get("/api/status").json()["state"] == "click_grab"
    live.wait_for(lambda: http.get("/api/jobs/current").json()["job"]["state"] != "running", 60)
    job = http.get("/api/jobs/current").json()["job"]
    assert job["state"] == "succeeded", job
    block = next(o for o in http.get("/api/sim/truth").json()["objects"] if o["id"] == "g")
    assert block["position_m"][2] > 0.05
    response = http.post("/api/drop", params={"wait": "true"}, json={"position_m": [0.1, 0.2, 0.0]}, headers=AUTH)
    assert response.status_code == 200 and response.json()["job"]["state"] == "succeeded", response.text
    live.wait_sim(cell, 0.4)  # the block settles
    block = next(o for o in http.get("/api/sim/truth").json()["objects"] if o["id"] == "g")
    assert np.hypot(block["position_m"][0] - 0.1, block["position_m"][1] - 0.2) < 0.010
    history = http.get("/api/jobs/history").json()["data"]
    assert [j["name"] for j in history[:3]] == ["drop", "grab", "calibrate"]


def test_unknown_paths_and_methods_are_json_errors(http):
    assert "/api/nonexistent" in _error(http.get("/api/nonexistent"), 404, "not_found")["message"]
    assert "DELETE" in _error(http.delete("/api/status"), 405, "invalid")["message"]
    _error(http.post("/api/programs/abc/repeat", headers=AUTH), 422, "invalid")


def test_jobs_cancel_and_wrong_state(http):
    _error(http.post("/api/jobs/cancel", headers=AUTH), 409, "wrong_state")
    assert http.get("/api/jobs/current").status_code == 200


def test_sim_scene_validation(http):
    blob = {"id": "x", "type": "blob", "color": "red", "position_m": [0, 0.2, 0]}
    _error(http.post("/api/sim/scene", json={"objects": [blob]}, headers=AUTH), 422, "invalid")
    assert http.post("/api/sim/scene", json={"event": "pick_sort", "level": 1, "seed": 2}, headers=AUTH).json()["objects"] == 3
    assert len(http.get("/api/sim/truth").json()["objects"]) == 3
    _error(http.post("/api/sim/scene", json={"event": "pick_sort"}), 401, "unauthorized")


def test_programs_survive_a_server_restart(cell, tmp_path):
    db_path = tmp_path / "restart.sqlite3"
    app = create_app(station_factory=lambda: live.StationOnCell(cell, db_path), token=TOKEN)
    with live.serve(app) as base_url, httpx.Client(base_url=base_url, timeout=30) as http:
        _idle(http)
        assert http.post("/api/teach/start", headers=AUTH).json()["state"] == "teach"
        _error(http.post("/api/teach/start", headers=AUTH), 409, "wrong_state")
        http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": [0.2, 0, 0, 0, 0], "moving_time_s": 0.5}, headers=AUTH)
        first = http.post("/api/teach/record", headers=AUTH).json()
        http.post("/api/gripper", json={"action": "grasp"}, headers=AUTH)
        http.post("/api/teach/record", headers=AUTH)
        _error(http.post("/api/teach/stop", json={"name": ""}, headers=AUTH), 422, "invalid")
        program = http.post("/api/teach/stop", json={"name": "pick demo"}, headers=AUTH).json()
        assert program["name"] == "pick demo" and len(program["waypoints"]) == 2
        assert np.allclose(program["waypoints"][0]["joints_rad"], first["joints_rad"])
        assert program["waypoints"][1]["gripper"] == "grasp"
        http.post("/api/gripper", json={"action": "release"}, headers=AUTH)
    # a new server process state: new app, new station, same database file
    app = create_app(station_factory=lambda: live.StationOnCell(cell, db_path), token=TOKEN)
    with live.serve(app) as base_url, httpx.Client(base_url=base_url, timeout=30) as http:
        programs = http.get("/api/programs").json()
        assert programs["count"] == 1 and programs["data"][0]["name"] == "pick demo"
        program_id = programs["data"][0]["id"]
        _error(http.post("/api/programs/999/repeat", json={"cycles": 1}, headers=AUTH), 404, "not_found")
        _error(http.post(f"/api/programs/{program_id}/repeat", json={"cycles": 0}, headers=AUTH), 422, "invalid")
        response = http.post(f"/api/programs/{program_id}/repeat", params={"wait": "true"}, json={"cycles": 1}, headers=AUTH)
        assert response.status_code == 200 and response.json()["job"]["state"] == "succeeded", response.text
        status = http.get("/api/status").json()
        assert status["gripper"]["command"] == "grasp"
        assert response.json()["job"]["extra"]["repeat"]["waypoint"] == 2  # it reached the last waypoint
        assert np.allclose(status["joints_rad"], 0.0, atol=0.02)  # and went home at the end (issue 9)
        http.post("/api/gripper", json={"action": "release"}, headers=AUTH)


def test_a_damaged_program_row_is_reported_and_skipped_not_a_500(cell, tmp_path):
    import sqlite3

    from armlab.store import Store, Waypoint

    db_path = tmp_path / "damaged-row.sqlite3"
    store = Store(db_path)
    good = store.save_program("good", [Waypoint((0.1, 0.0, 0.0, 0.0, 0.0), "release")])
    connection = sqlite3.connect(db_path)
    with connection:
        connection.execute("INSERT INTO programs (name, created_s, waypoints_json) VALUES (CAST(X'ff' AS TEXT), 1.0, '[]')")
        bad_id = connection.execute("SELECT max(id) FROM programs").fetchone()[0]
    connection.close()
    app = create_app(station_factory=lambda: live.StationOnCell(cell, db_path), token=TOKEN)
    with live.serve(app) as base_url, httpx.Client(base_url=base_url, timeout=30) as http:
        listing = http.get("/api/programs")
        assert listing.status_code == 200, listing.text
        body = listing.json()
        assert [p["id"] for p in body["data"]] == [good.id] and body["count"] == 1
        assert len(body["skipped"]) == 1 and f"program {bad_id}" in body["skipped"][0] and "UTF-8" in body["skipped"][0]
        assert "damaged" in _error(http.get(f"/api/programs/{bad_id}"), 404, "not_found")["message"]
        _error(http.post(f"/api/programs/{bad_id}/repeat", headers=AUTH), 404, "not_found")
        assert http.delete(f"/api/programs/{bad_id}", headers=AUTH).json() == {"deleted": bad_id}
        assert http.get("/api/programs").json()["skipped"] == []
