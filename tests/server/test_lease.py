"""The control lease over real HTTP and websockets (issue 10 item 3): exactly one controller; moves from
anyone else are refused (409 naming the controller) and move nothing; the lease is visible to everyone;
it changes hands only by an explicit take-over, which the previous controller is told about; e-stop needs
no lease; a page's lease ends with its last websocket. Also the two decisions of item 3: the scheme name
of 'Authorization: bearer' is case-insensitive (RFC 7235) and pixel-to-world stays open to viewers."""

from __future__ import annotations

import json
import time

import httpx
import numpy as np
import pytest
from websockets.exceptions import WebSocketException
from websockets.sync.client import connect

import live

TOKEN = "lease-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
ALICE = {**AUTH, "X-Armlab-Controller": "alice"}
BOB = {**AUTH, "X-Armlab-Controller": "bob"}
CAROL = {**AUTH, "X-Armlab-Controller": "carol"}
GOAL_A = [0.6, 0.2, 0.1, 0.3, 0.0]
GOAL_B = [-0.6, 0.2, 0.1, 0.3, 0.0]


cell, url = live.module_fixtures(seed=13, token=TOKEN)


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=30.0) as client:
        _free(client)
        yield client
        _free(client)


def _free(client) -> None:
    """Idle, not moving, nobody in control."""
    client.post("/api/control/take", headers=AUTH)
    if client.get("/api/status").json()["state"] != "idle":
        client.post("/api/estop", headers=AUTH)
        client.post("/api/reset", headers=AUTH)
    live.wait_for(lambda: not client.get("/api/status").json()["moving"], 15)
    client.post("/api/control/release", headers=AUTH)
    assert client.get("/api/status").json()["controller"] is None


def _error(response, status_code: int, code: str) -> str:
    assert response.status_code == status_code, response.text
    body = response.json()["error"]
    assert body["code"] == code
    return body["message"]


def _joints(client) -> np.ndarray:
    return np.array(client.get("/api/status").json()["joints_rad"])


def _ws(url: str, query: str = ""):
    return connect(url.replace("http://", "ws://") + "/ws" + query, compression=None, max_size=None, open_timeout=10, close_timeout=2)


def _events_until(ws, fragment: str, timeout_s: float = 5.0) -> dict:
    deadline = time.monotonic() + timeout_s
    while True:
        message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(message, str):
            parsed = json.loads(message)
            if parsed["type"] == "event" and fragment in parsed["message"]:
                return parsed


def test_a_second_client_cannot_reverse_a_move_in_progress(http):
    response = http.post("/api/arm/joints", json={"q_rad": GOAL_A, "moving_time_s": 2.0}, headers=ALICE)
    assert response.status_code == 200 and response.json()["controller"] == "alice"
    message = _error(http.post("/api/arm/joints", json={"q_rad": GOAL_B, "moving_time_s": 2.0}, headers=BOB), 409, "not_controller")
    assert "'alice'" in message and "take control" in message
    # Everyone sees who controls, without the token too.
    assert httpx.get(http.base_url.join("/api/status")).json()["controller"] == "alice"
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 15)
    assert np.allclose(_joints(http), GOAL_A, atol=0.03), "the refused move changed the motion"
    for path, body in (("/api/arm/home", None), ("/api/gripper", {"action": "grasp"}), ("/api/teach/start", None), ("/api/reset", None)):
        response = http.post(path, json=body, headers=BOB)
        assert response.status_code == 409, (path, response.text)


def test_take_over_is_explicit_and_the_previous_controller_is_told(http, url):
    with _ws(url, f"?token={TOKEN}&controller=alice") as page:
        hello = json.loads(page.recv(timeout=5))
        assert hello["controller"] == "alice"
        assert http.post("/api/arm/home", json={"moving_time_s": 1.0}, headers=ALICE).json()["controller"] == "alice"
        status = http.post("/api/control/take", headers=BOB).json()
        assert status["controller"] == "bob" and status["controller_since_s"] > 0
        event = _events_until(page, "control taken by 'bob' from 'alice'")
        assert event["level"] == "warn"
        message = _error(http.post("/api/arm/sleep", headers=ALICE), 409, "not_controller")
        assert "'bob'" in message
    assert http.post("/api/arm/home", json={"moving_time_s": 1.0}, params={"wait": "true"}, headers=BOB).status_code == 200


def test_estop_needs_no_lease_and_does_not_take_it(http):
    assert http.post("/api/arm/joints", json={"q_rad": GOAL_B, "moving_time_s": 3.0}, headers=ALICE).status_code == 200
    live.wait_for(lambda: http.get("/api/status").json()["moving"], 5)
    status = http.post("/api/estop", headers=CAROL).json()
    assert status["state"] == "estop" and status["controller"] == "alice" and "carol" in status["detail"]
    _error(http.post("/api/reset", headers=CAROL), 409, "not_controller")
    assert http.post("/api/reset", headers=ALICE).json()["state"] == "idle"


def test_a_pages_lease_ends_with_its_last_websocket(http, url):
    with _ws(url, f"?token={TOKEN}&controller=page-1") as page:
        json.loads(page.recv(timeout=5))
        page.send(json.dumps({"type": "command", "name": "take_control"}))
        live.wait_for(lambda: http.get("/api/status").json()["controller"] == "page-1", 5)
        # The page's own REST calls carry its name and are accepted; a script's are not.
        assert http.post("/api/gripper", json={"action": "release"}, headers={**AUTH, "X-Armlab-Controller": "page-1"}).status_code == 200
        _error(http.post("/api/gripper", json={"action": "grasp"}, headers=AUTH), 409, "not_controller")
        with _ws(url, f"?token={TOKEN}&controller=page-1") as second_tab:
            json.loads(second_tab.recv(timeout=5))
        assert http.get("/api/status").json()["controller"] == "page-1"  # one of its sessions is still open
    live.wait_for(lambda: http.get("/api/status").json()["controller"] is None, 5)


def test_a_view_only_session_cannot_take_control(http, url):
    with _ws(url) as viewer:
        assert json.loads(viewer.recv(timeout=5))["controller"] is None
        viewer.send(json.dumps({"type": "command", "name": "take_control"}))
        assert "view-only" in _events_until(viewer, "refused")["message"]
    assert http.get("/api/status").json()["controller"] is None


def test_controller_names_are_checked(http, url):
    _error(http.post("/api/arm/home", headers={**AUTH, "X-Armlab-Controller": "bad name!"}), 422, "invalid")
    with pytest.raises(WebSocketException), _ws(url, f"?token={TOKEN}&controller=" + "x" * 65) as ws:
        ws.recv(timeout=5)


def test_decisions_lowercase_bearer_and_open_pixel_to_world(http, cell):
    # RFC 7235: the scheme name is case-insensitive, so 'bearer' works like 'Bearer'.
    lower = {"Authorization": f"bearer {TOKEN}", "X-Armlab-Controller": "alice"}
    assert http.post("/api/gripper", json={"action": "release"}, headers=lower).status_code == 200
    # pixel-to-world is read-only (no token): it answers from the calibration viewers can already read
    # (409 until calibrated) and moves nothing.
    q = _joints(http)
    response = http.post("/api/pixel-to-world", json={"u": 640, "v": 360})
    assert response.status_code in (200, 409)
    assert response.status_code != 401
    assert np.allclose(_joints(http), q, atol=2e-3)


def test_program_edits_need_the_lease_reading_does_not(http):
    """Issue 18 item 7: a client without the lease cannot rename, replace, delete, duplicate or import the
    holder's programs (409 naming the holder, nothing stored changes); reading and exporting stay open."""
    taught = {"name": "alice's", "format": "json", "content": json.dumps(
        {"name": "alice's", "joint_names": ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"],
         "waypoints": [{"joints_rad": [0.0, 0.0, 0.0, 0.0, 0.0], "gripper": "release"},
                       {"joints_rad": GOAL_A, "gripper": "grasp"}]})}
    response = http.post("/api/programs/import", json=taught, headers=ALICE)
    assert response.status_code == 201, response.text
    program = response.json()
    assert http.get("/api/status").json()["controller"] == "alice"
    pid = program["id"]
    before = http.get("/api/programs").json()
    refused = [
        http.patch(f"/api/programs/{pid}", json={"name": "bob's now"}, headers=BOB),
        http.patch(f"/api/programs/{pid}", json={"waypoints": [{"joints_rad": GOAL_B, "gripper": "release"}]}, headers=BOB),
        http.delete(f"/api/programs/{pid}", headers=BOB),
        http.post(f"/api/programs/{pid}/duplicate", json={"name": "copied by bob"}, headers=BOB),
        http.post("/api/programs/import", json={**taught, "name": "bob's import"}, headers=BOB),
    ]
    for response in refused:
        assert "'alice'" in _error(response, 409, "not_controller"), response.request.url
    assert http.get("/api/programs").json() == before, "a refused edit changed the stored programs"
    # Reading needs neither the lease nor the token.
    assert httpx.get(http.base_url.join(f"/api/programs/{pid}")).json()["name"] == "alice's"
    assert httpx.get(http.base_url.join(f"/api/programs/{pid}/export")).status_code == 200
    # The holder edits as before.
    assert http.patch(f"/api/programs/{pid}", json={"name": "renamed"}, headers=ALICE).json()["name"] == "renamed"
    assert http.post(f"/api/programs/{pid}/duplicate", headers=ALICE).status_code == 201
    assert http.delete(f"/api/programs/{pid}", headers=ALICE).json() == {"deleted": pid}
