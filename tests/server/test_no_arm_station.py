"""A station with no arm (`armlab serve --arm none`) on a recorded camera, over real HTTP and the websocket:
every command that needs the arm is refused (409 no_arm, the reason in the message, nothing planned), while
status, the stream, frames, detections, calibration routes, programs listing and e-stop/reset work."""

from __future__ import annotations

import json
import time

import httpx
import pytest
from websockets.sync.client import connect

from armlab.station import StationConfig
from armlab.store import Waypoint
from live import serve
from recorded_helpers import write_pairs

TOKEN = "no-arm-token"
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "operator"}
REASON = "this station has no arm"


@pytest.fixture(scope="module")
def station_url(tmp_path_factory):
    from armlab.station.factory import make_device_station
    from server.app import create_app

    folder = tmp_path_factory.mktemp("recording")
    write_pairs(folder)
    db = folder / "station.sqlite3"
    made = make_device_station(StationConfig(database_path=str(db)), "none", "none",
                               {"type": "recorded", "source": str(folder), "fps": 10}, db_path=db)
    program = made.station.store.save_program("taught elsewhere", [Waypoint((0.0, 0.1, 0.2, 0.3, 0.0), "release", 0.0, None)])
    app = create_app(station_factory=lambda: made, token=TOKEN)
    with serve(app) as url:
        yield made.station, url, program.id


MOTION_ROUTES = [
    ("POST", "/api/arm/home", None),
    ("POST", "/api/arm/sleep", None),
    ("POST", "/api/arm/joints", {"q_rad": [0.0, 0.1, 0.2, 0.3, 0.0]}),
    ("POST", "/api/arm/pose", {"position_m": [0.2, 0.1, 0.1]}),
    ("POST", "/api/arm/torque", {"enabled": False, "confirm": True}),
    ("POST", "/api/arm/jog", {"velocity_rad_s": [0.1, 0.0, 0.0, 0.0, 0.0]}),
    ("POST", "/api/arm/jog/cartesian", {"axis": "x", "velocity_m_s": 0.05}),
    ("POST", "/api/arm/step", {"axis": "x", "distance_m": 0.01}),
    ("POST", "/api/gripper", {"action": "grasp"}),
    ("POST", "/api/grab", {"position_m": [0.1, 0.2, 0.0]}),
    ("POST", "/api/drop", {"u": 640, "v": 360}),
    ("POST", "/api/teach/start", None),
    ("POST", "/api/teach/record", None),
    ("POST", "/api/teach/undo", None),
    ("POST", "/api/teach/stop", {"name": "x"}),
    ("POST", "/api/teach/continuous", {"rate_hz": 2.0}),
    ("POST", "/api/teach/continuous/stop", None),
    ("POST", "/api/programs/{program}/repeat", {"cycles": 1}),
    ("POST", "/api/jobs/pause", None),
    ("POST", "/api/jobs/resume", None),
    ("POST", "/api/jobs/step", None),
    ("PATCH", "/api/jobs/current", {"speed_percent": 50}),
    ("POST", "/api/auto", {"job": "pick_sort", "level": 1}),
    ("PATCH", "/api/programs/{program}", {"waypoints": [{"joints_rad": [0.0, 0.0, 0.0, 0.0, 0.0], "gripper": "release"}]}),
    ("GET", "/api/programs/{program}/export?format=csv", None),
    ("POST", "/api/programs/import", {"format": "csv", "content": "t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n"}),
]


@pytest.mark.parametrize("method, path, body", MOTION_ROUTES, ids=[f"{m} {p}" for m, p, _ in MOTION_ROUTES])
def test_every_arm_route_is_refused_with_the_reason(station_url, method, path, body):
    station, url, program_id = station_url
    response = httpx.request(method, url + path.format(program=program_id), json=body, headers=AUTH, timeout=10)
    assert response.status_code == 409, response.text
    error = response.json()["error"]
    assert error["code"] == "no_arm" and REASON in error["message"], error
    assert not any(name in error["allowed"] for name in ("home", "jog", "grab", "repeat", "auto", "teach_start"))
    status = httpx.get(url + "/api/status", timeout=10).json()
    assert status["state"] == "idle" and status["devices_lost"] == {} and status["job"] is None


def test_status_and_the_perception_routes_work_without_joints(station_url):
    station, url, program_id = station_url
    status = httpx.get(url + "/api/status", timeout=10).json()
    assert status["joints_rad"] == [] and status["joint_names"] == [] and status["gripper_pose"] is None
    assert status["allowed_commands"] == ["estop", "calibrate", "set_scene"] and status["backend"] == "real"
    arm = httpx.get(url + "/api/arm", timeout=10).json()
    assert arm["has_arm"] is False and arm["joint_names"] == [] and REASON in arm["reason"]
    for path in ("/api/detections", "/api/calibration", "/api/intrinsics", "/api/auto/jobs", "/api/jobs/current", "/api/teach/draft"):
        assert httpx.get(url + path, timeout=10).status_code == 200, path
    programs = httpx.get(url + "/api/programs", timeout=10).json()
    assert programs["data"][0]["waypoints"][0]["gripper_position_m"] is None  # no arm: no gripper point to draw
    frame = httpx.get(url + "/api/frame.jpg?view=color&layers=tags,detections,grid", timeout=10)
    assert frame.status_code == 200 and frame.content[:2] == b"\xff\xd8"
    depth = httpx.get(url + "/api/frame.jpg?view=depth", timeout=10)
    assert depth.status_code == 200
    click = httpx.post(url + "/api/pixel-to-world", json={"u": 10, "v": 10}, timeout=10)
    assert click.status_code == 409 and click.json()["error"]["code"] == "not_calibrated"
    renamed = httpx.patch(url + f"/api/programs/{program_id}", json={"name": "renamed"}, headers=AUTH, timeout=10)
    assert renamed.status_code == 200 and renamed.json()["name"] == "renamed"  # a rename needs no arm


def test_the_3d_scene_is_the_workcell_without_an_arm(station_url):
    _station, url, _program_id = station_url
    scene = httpx.get(url + "/api/view3d/scene", timeout=10).json()
    assert scene["arm"] is None and scene["workcell"]["board"]["x_range_m"] and scene["workcell"]["board_tags"]["centres_m"]
    urdf = httpx.get(url + "/api/view3d/arm.urdf", timeout=10)
    assert urdf.status_code == 404 and "no arm" in urdf.json()["error"]["message"]
    points = httpx.get(url + "/api/view3d/points", timeout=10)
    assert points.status_code == 409 and points.json()["error"]["code"] == "not_calibrated"


def test_the_stream_says_there_is_no_arm_and_estop_and_reset_work(station_url):
    station, url, _ = station_url
    ws_url = url.replace("http://", "ws://") + f"/ws?token={TOKEN}&controller=operator"
    with connect(ws_url, compression=None, max_size=None, open_timeout=10, close_timeout=2) as ws:
        seen = {}
        deadline = time.monotonic() + 10
        while ("hello" not in seen or "telemetry" not in seen or "frame" not in seen) and time.monotonic() < deadline:
            message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
            if isinstance(message, bytes):
                seen["frame"] = True  # one frame in flight: no ack needed for this test
            else:
                data = json.loads(message)
                seen.setdefault(data["type"], data)
        assert seen["hello"]["arm"]["has_arm"] is False and REASON in seen["hello"]["arm"]["reason"]
        assert seen["telemetry"]["joints_rad"] == [] and seen["frame"]
        ws.send(json.dumps({"type": "command", "name": "estop"}))
        deadline = time.monotonic() + 5
        while station.state.value != "estop" and time.monotonic() < deadline:
            ws.recv(timeout=1)
    assert station.state.value == "estop"
    reset = httpx.post(url + "/api/reset", headers=AUTH, timeout=10)
    assert reset.status_code == 200 and reset.json()["state"] == "idle"
