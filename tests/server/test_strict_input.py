"""Strict request types over real HTTP (issue 10, item 2): no bool/number/string coercion, angles
bounded, ids beyond SQLite's range and malformed scene objects are 4xx (never 500), the OpenAPI schema
says so, nothing moves on a refused request; malformed websocket messages get an error message and the
session stays open."""

from __future__ import annotations

import json
import math
import time

import httpx
import numpy as np
import pytest
from websockets.sync.client import connect

import live

TOKEN = "strict-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
POSE = {"position_m": [0.0, 0.25, 0.12]}
SQLITE_MAX = 2**63 - 1


cell, url = live.module_fixtures(seed=3, token=TOKEN)


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=30.0) as client:
        yield client


def _still(http) -> dict:
    """The status once the arm is at rest (no move in progress)."""
    return live.wait_for(lambda: (s := http.get("/api/status").json()) and not s["moving"] and s, 10)


@pytest.mark.parametrize(
    ("path", "body", "field"),
    [
        ("/api/arm/pose", {**POSE, "pitch_rad": False}, "pitch_rad"),
        ("/api/arm/pose", {**POSE, "yaw_rad": "0.5"}, "yaw_rad"),
        ("/api/arm/pose", {**POSE, "yaw_rad": 1e308}, "yaw_rad"),
        ("/api/arm/pose", {**POSE, "pitch_rad": 7.0}, "pitch_rad"),
        ("/api/arm/pose", {"position_m": [0.0, "0.25", 0.12]}, "position_m"),
        ("/api/arm/pose", {"position_m": [0.0, True, 0.12]}, "position_m"),
        ("/api/arm/pose", {"position_m": [0.0, 1e300, 0.12]}, "position_m"),
        ("/api/arm/joints", {"q_rad": [0.3, 0, 0, 0, 0], "moving_time_s": True}, "moving_time_s"),
        ("/api/arm/joints", {"q_rad": [0.3, 0, 0, 0, 0], "moving_time_s": "1"}, "moving_time_s"),
        ("/api/arm/joints", {"q_rad": [True, 0, 0, 0, 0]}, "q_rad"),
        ("/api/arm/joints", {"q_rad": ["0.3", 0, 0, 0, 0]}, "q_rad"),
        ("/api/arm/joints", {"q_rad": [1e308, 0, 0, 0, 0]}, "q_rad"),
        ("/api/arm/home", {"moving_time_s": True}, "moving_time_s"),
        ("/api/arm/torque", {"enabled": 0}, "enabled"),
        ("/api/arm/torque", {"enabled": "false"}, "enabled"),
        ("/api/gripper", {"action": 1}, "action"),
        ("/api/teach/stop", {"name": 5}, "name"),
        ("/api/pixel-to-world", {"u": "640", "v": 360}, "u"),
        ("/api/pixel-to-world", {"u": True, "v": 360}, "u"),
        ("/api/grab", {"u": 640, "v": False}, "v"),
        ("/api/sim/scene", {"event": "pick_sort", "level": True, "seed": 1}, "level"),
        ("/api/sim/scene", {"event": "pick_sort", "level": 1, "seed": "1"}, "seed"),
        ("/api/sim/scene", {"event": "no_such_event", "level": 1, "seed": 1}, "event"),
        ("/api/sim/scene", {"objects": [{"id": "a", "type": "block", "color": "red", "size": "large",
                                         "position_m": [0, 0.25, 0.02], "quat_wxyz": 5}]}, "quat_wxyz"),
        ("/api/sim/scene", {"objects": [{"id": "a", "type": "block", "color": "red", "position_m": "here"}]}, "position_m"),
        ("/api/sim/scene", {"objects": [5]}, "objects"),
    ],
)
def test_coerced_or_out_of_range_input_is_422_and_moves_nothing(http, path, body, field):
    before = _still(http)
    response = http.post(path, json=body, headers=AUTH)
    assert response.status_code == 422, response.text
    error = response.json()["error"]
    assert error["code"] == "invalid" and field in error["message"], error
    after = http.get("/api/status").json()
    assert not after["moving"] and after["state"] == before["state"]
    assert np.allclose(after["joints_rad"], before["joints_rad"], atol=2e-3)
    assert after["gripper"]["command"] == before["gripper"]["command"]


def test_torque_stays_on_after_a_coerced_torque_off(http):
    http.post("/api/arm/torque", json={"enabled": 0}, headers=AUTH)
    before = _still(http)
    # Watch 0.5 s of the station's clock: a limp arm sags visibly in that time (0.76 rad in 3 s).
    after = live.wait_for(lambda: (s := http.get("/api/status").json())["time_s"] >= before["time_s"] + 0.5 and s, 5)
    assert np.allclose(after["joints_rad"], before["joints_rad"], atol=5e-3)


@pytest.mark.parametrize("program_id", [str(SQLITE_MAX + 1), str(-(SQLITE_MAX + 2)), "1" + "0" * 40, "0", "-1"])
def test_program_ids_beyond_sqlite_are_client_errors(http, program_id):
    for method, path in (("GET", f"/api/programs/{program_id}"), ("DELETE", f"/api/programs/{program_id}"),
                         ("POST", f"/api/programs/{program_id}/repeat")):
        response = http.request(method, path, headers=AUTH)
        assert response.status_code in (404, 422), (method, path, response.text)
        assert response.json()["error"]["code"] in ("not_found", "invalid")


def test_the_openapi_schema_states_types_and_bounds(http):
    schemas = http.get("/openapi.json").json()["components"]["schemas"]
    pose = schemas["PoseRequest"]["properties"]
    yaw = next(option for option in pose["yaw_rad"]["anyOf"] if option.get("type") == "number")
    assert yaw["minimum"] == pytest.approx(-2 * math.pi) and yaw["maximum"] == pytest.approx(2 * math.pi)
    q_item = schemas["JointsRequest"]["properties"]["q_rad"]["items"]
    assert q_item["type"] == "number" and q_item["maximum"] == pytest.approx(2 * math.pi)
    assert schemas["TorqueRequest"]["properties"]["enabled"]["type"] == "boolean"
    scene_object = schemas["SceneObjectRequest"]["properties"]
    assert scene_object["quat_wxyz"]["anyOf"][0]["type"] == "array"
    paths = http.get("/openapi.json").json()["paths"]
    program_id = next(p for p in paths["/api/programs/{program_id}"]["get"]["parameters"] if p["name"] == "program_id")
    assert program_id["schema"]["maximum"] == SQLITE_MAX and program_id["schema"]["minimum"] >= 0


def _ws(url: str):
    ws_url = url.replace("http://", "ws://") + f"/ws?token={TOKEN}"
    return connect(ws_url, compression=None, max_size=None, open_timeout=10, close_timeout=2)


def _next_text(ws, kind: str, timeout_s: float = 5.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while True:
        message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(message, str) and json.loads(message)["type"] == kind:
            return json.loads(message)


@pytest.mark.parametrize(
    "message",
    [
        b"\x00\x01binary",
        '{"type": "command", "name": ["estop"]}',
        '{"type": ["command"], "name": "estop"}',
        '{"type": "command", "name": {"a": 1}}',
        '{"type": "view", "layers": [["tags"]]}',
        '{"type": "view", "view": ["color"]}',
        '{"type": "ack", "seq": [1]}',
        '[1, 2, 3]',
        '"estop"',
        "not json",
    ],
)
def test_a_malformed_websocket_message_gets_an_error_and_the_session_stays_open(http, url, message):
    with _ws(url) as ws:
        assert _next_text(ws, "hello")["can_control"] is True
        ws.send(message)
        error = _next_text(ws, "event")
        assert error["level"] == "error" and len(error["message"]) > 10
        ws.send(json.dumps({"type": "view", "view": "color", "layers": ["grid"]}))  # still served after the error
        assert _next_text(ws, "telemetry")["state"] == "idle"
    assert http.get("/api/status").json()["state"] == "idle"  # the list-named 'estop' did not stop anything


_HEADER = "t_s,q1,q2,q3,q4,q5,gripper\n"
_JOINT_NAMES = ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"]


@pytest.mark.parametrize(
    ("file_format", "content", "fragment"),
    [
        ("csv", _HEADER + "0," + "1" * 140_000 + ",0,0,0,0,release\n", "line 2"),  # a field over csv's 131,072 limit
        ("csv", _HEADER + '0,"' + "x" * 140_000 + "\n", "line 2"),  # an unclosed quote swallowing the rest
        ("json", "[" * 100_000 + "]" * 100_000, "nested"),
        ("json", json.dumps({"waypoints": [{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release"}]}).replace("[0, 0", "[1" + "0" * 400 + ", 0", 1),
         "joints_rad"),
        ("csv", _HEADER + "0,1" + "0" * 400 + ",0,0,0,0,release\n", "q1"),
        ("json", json.dumps({"name": "n" * 500_000, "joint_names": _JOINT_NAMES,
                             "waypoints": [{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release"}]}), "name"),
    ],
    ids=["csv-field-over-limit", "csv-unclosed-quote", "json-nested-100k", "json-joint-10e400", "csv-joint-10e400", "json-name-500k"],
)
def test_malformed_program_files_are_422_and_store_nothing(http, file_format, content, fragment):
    """Issue 18 item 8: each of these was a 500 (or, for the name, stored 500,000 characters)."""
    before = http.get("/api/programs").json()
    response = http.post("/api/programs/import", json={"format": file_format, "content": content}, headers=AUTH)
    assert response.status_code == 422, response.text[:300]
    error = response.json()["error"]
    assert error["code"] == "invalid" and fragment in error["message"], error["message"][:300]
    assert http.get("/api/programs").json() == before


def _block(index: int, position_m: list[float]) -> dict:
    return {"id": f"b{index}", "type": "block", "color": "red", "size": "large", "position_m": position_m}


@pytest.mark.parametrize(
    ("objects", "fragment"),
    [
        ([_block(0, [0.10, 0.20, 0.019]), _block(1, [0.12, 0.20, 0.019])], "b0 and b1 overlap"),
        ([_block(0, [0.10, 0.20, -1.0])], "b0 is below the board"),
        ([_block(0, [0.10, 0.20, 0.010])], "b0 is below the board"),  # 9 mm into the board
        ([_block(i, [0.10, 0.20, 0.019]) for i in range(100)], "overlap"),  # exhausted MuJoCo's arena: a fault
    ],
    ids=["two-overlapping", "one-metre-below", "half-sunk", "hundred-in-one-place"],
)
def test_scenes_that_cannot_stand_are_422_and_change_nothing(http, objects, fragment):
    """Issue 18 item 8: a block at z = -1 m was flung to z = 98.8 m, 100 overlapping blocks faulted the station."""
    scene = [_block(0, [-0.10, 0.20, 0.019]), _block(1, [0.10, 0.20, 0.019 + 0.038])]  # a block on a block only touches
    assert http.post("/api/sim/scene", json={"objects": scene}, headers=AUTH).status_code == 200
    response = http.post("/api/sim/scene", json={"objects": objects}, headers=AUTH)
    assert response.status_code == 422, response.text[:300]
    error = response.json()["error"]
    assert error["code"] == "invalid" and fragment in error["message"], error["message"][:300]
    assert http.get("/api/sim/scene").json()["objects"] == 2
    assert http.get("/api/status").json()["state"] == "idle"
