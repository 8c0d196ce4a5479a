"""The websocket stream over a real server with a real `websockets` client: hello, telemetry, frames
with headers, ack flow control (at most one frame in flight), views, control messages and auth."""

from __future__ import annotations

import json
import time

import cv2
import httpx
import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

import live
from armlab.client import unpack_frame

TOKEN = "ws-token"


cell, http_url = live.module_fixtures(seed=1, token=TOKEN)


@pytest.fixture(scope="module")
def url(http_url):
    return http_url.replace("http://", "ws://") + "/ws"


def _open(url: str, token: str | None = None):
    return connect(url + (f"?token={token}" if token else ""), compression=None, max_size=None, open_timeout=10, close_timeout=2)


def _next(ws, kind: str, timeout_s: float = 5.0):
    """The next message of `kind` ('frame' for binary), skipping others."""
    deadline = time.monotonic() + timeout_s
    while True:
        message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        if isinstance(message, bytes):
            if kind == "frame":
                return unpack_frame(message)
        elif json.loads(message)["type"] == kind:
            return json.loads(message)


def _collect(ws, duration_s: float) -> tuple[list, list]:
    """(frames, texts) received during duration_s, without acknowledging anything."""
    frames, texts = [], []
    deadline = time.monotonic() + duration_s
    while True:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return frames, texts
        try:
            message = ws.recv(timeout=remaining)
        except TimeoutError:
            return frames, texts
        (frames if isinstance(message, bytes) else texts).append(message)


def test_hello_calibration_and_telemetry(url):
    with _open(url, TOKEN) as ws:
        hello = json.loads(ws.recv(timeout=5))
        assert hello["type"] == "hello" and hello["can_control"] is True and hello["backend"] == "sim"
        assert abs(hello["server_time_s"] - time.time()) < 5
        workcell = hello["workcell"]  # the workcell geometry the browser draws with (DESIGN §3)
        assert workcell["board"]["x_range_m"] == [-0.5, 0.5] and workcell["board"]["y_range_m"] == [-0.175, 0.475]
        assert workcell["block_edges_m"] == {"large": 0.038, "small": 0.025}
        calibration = json.loads(ws.recv(timeout=5))
        assert calibration["type"] == "calibration" and "calibrated" in calibration
        first = _next(ws, "telemetry")
        for field in ("state", "joints_rad", "gripper", "gripper_pose", "allowed_commands", "detections", "job", "time_s"):
            assert field in first
        started = time.monotonic()
        count = 0
        while time.monotonic() - started < 1.0:
            _next(ws, "telemetry")
            count += 1
        assert count >= 15  # published at 30 Hz; the bench prints the measured rate


def test_frames_carry_headers_and_decode(url):
    with _open(url) as ws:
        header, jpeg = _next(ws, "frame")
        assert header["type"] == "frame" and header["view"] == "color"
        assert (header["width"], header["height"]) == (1280, 720)
        assert isinstance(header["seq"], int) and 0 <= time.time() - header["capture_time_s"] < 2.0
        image = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
        assert image.shape == (720, 1280, 3)
        ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
        second, _ = _next(ws, "frame")
        assert second["seq"] > header["seq"] and second["capture_time_s"] > header["capture_time_s"]


def test_a_client_that_never_acks_gets_one_frame_in_flight(url):
    with _open(url) as ws:
        frames, texts = _collect(ws, 1.5)
        assert len(frames) == 1, f"{len(frames)} frames sent without an ack"
        assert sum(json.loads(t)["type"] == "telemetry" for t in texts) >= 10  # telemetry keeps flowing
        header, _ = unpack_frame(frames[0])
        ws.send(json.dumps({"type": "ack", "seq": header["seq"] + 1000}))  # an ack for another frame releases nothing
        frames, _ = _collect(ws, 0.5)
        assert frames == []
        ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
        frames, _ = _collect(ws, 1.0)
        assert len(frames) == 1
        newer, _ = unpack_frame(frames[0])
        assert newer["seq"] > header["seq"] + 1, "the next frame is the newest, not the one after the acked one"


def test_acking_client_streams_while_a_stalled_client_is_connected(url):
    with _open(url) as stalled, _open(url) as reader:
        _next(stalled, "frame")  # the stalled client holds its one frame and never acks
        sequences = []
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:
            header, _ = _next(reader, "frame")
            sequences.append(header["seq"])
            reader.send(json.dumps({"type": "ack", "seq": header["seq"]}))
        assert len(sequences) >= 6 and sequences == sorted(set(sequences))
        frames, _ = _collect(stalled, 0.3)
        assert frames == [], "the stalled client was sent more frames without acking"


def test_view_switch_and_layers(url):
    with _open(url) as ws:
        header, _ = _next(ws, "frame")
        ws.send(json.dumps({"type": "view", "view": "depth", "layers": ["grid", "tags"]}))
        ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
        deadline = time.monotonic() + 5
        while True:
            header, jpeg = _next(ws, "frame")
            ws.send(json.dumps({"type": "ack", "seq": header["seq"]}))
            if header["view"] == "depth":
                break
            assert time.monotonic() < deadline
        assert cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR).shape == (720, 1280, 3)
        ws.send(json.dumps({"type": "view", "view": "xray"}))
        error = _next(ws, "event")
        assert error["level"] == "error" and "view" in error["message"]


def test_control_needs_the_token(url):
    with _open(url) as viewer:
        assert json.loads(viewer.recv(timeout=5))["can_control"] is False
        viewer.send(json.dumps({"type": "command", "name": "reset"}))
        event = _next(viewer, "event")
        assert event["level"] == "error" and "view-only" in event["message"]
        assert _next(viewer, "telemetry")["state"] == "idle"
    with _open(url, TOKEN) as controller:
        hello = json.loads(controller.recv(timeout=5))
        assert hello["can_control"] is True and hello["controller"].startswith("ws-")  # a name of its own
        controller.send(json.dumps({"type": "command", "name": "estop"}))
        deadline = time.monotonic() + 5
        while _next(controller, "telemetry")["state"] != "estop":
            assert time.monotonic() < deadline
        controller.send(json.dumps({"type": "command", "name": "reset"}))
        while _next(controller, "telemetry")["state"] != "idle":
            assert time.monotonic() < deadline
        assert _next(controller, "telemetry")["controller"] == hello["controller"]  # reset took the free lease


def test_wrong_token_is_rejected(url):
    with pytest.raises(ConnectionClosed) as closed, _open(url, "not-the-token") as ws:
        ws.recv(timeout=5)
    assert closed.value.rcvd.code == 4401


def test_a_view_only_session_and_a_tokenless_request_can_stop_the_arm(url, http_url):
    """Stopping never needs the token nor the lease (issue 9 item 3); other sites stay out (the Origin guard)."""
    auth = {"Authorization": f"Bearer {TOKEN}"}
    with _open(url) as viewer:
        assert json.loads(viewer.recv(timeout=5))["can_control"] is False
        viewer.send(json.dumps({"type": "command", "name": "estop"}))
        deadline = time.monotonic() + 5
        while _next(viewer, "telemetry")["state"] != "estop":
            assert time.monotonic() < deadline
    assert httpx.post(http_url + "/api/reset", headers=auth).json()["state"] == "idle"
    foreign = httpx.post(http_url + "/api/estop", headers={"Origin": "http://evil.example"})
    assert foreign.status_code == 403 and httpx.get(http_url + "/api/status").json()["state"] == "idle"
    answer = httpx.post(http_url + "/api/estop", headers={"X-Armlab-Controller": "viewer-page"})
    assert answer.status_code == 200 and answer.json()["state"] == "estop"
    assert httpx.post(http_url + "/api/reset", headers=auth).json()["state"] == "idle"


def test_a_websocket_estop_latches_while_a_slow_message_of_the_same_session_is_in_flight(cell, tmp_path):
    """A websocket e-stop is never queued behind a slow message of the same session (issue 20 item 6). The slow
    message: a take_control while the test holds the station's lock (as a long locked section or slow station call
    would); the e-stop sent after it must set the latch while it is still in flight (measured by the latch and the
    state, not by wall time). Its own station on the module's cell."""
    from armlab.station import State
    from server.app import create_app

    made = []

    def factory():
        made.append(live.StationOnCell(cell, tmp_path / "station.sqlite3"))
        return made[-1]

    with live.serve(create_app(station_factory=factory, token=TOKEN)) as url:
        station = made[0].station
        with connect(url.replace("http://", "ws://") + f"/ws?token={TOKEN}&controller=slow", open_timeout=10) as ws:
            assert json.loads(ws.recv(timeout=5))["type"] == "hello"
            _next(ws, "calibration")  # the session is set up (reading the calibration takes the lock too)
            assert not station.latch.is_set()
            with station._lock:  # take_control now waits for the lock on its worker thread
                ws.send(json.dumps({"type": "command", "name": "take_control"}))
                ws.send(json.dumps({"type": "command", "name": "estop"}))
                # before: the receive loop awaited take_control, so the e-stop waited for this lock
                live.wait_for(station.latch.is_set, 10.0)
                assert station.controller is None  # the slow message is indeed still in flight
            live.wait_for(lambda: station.state is State.ESTOP, 10.0)
            live.wait_for(lambda: station.controller == "slow", 10.0)  # and it still ran, in order, after


def test_heartbeats_queued_behind_a_slow_call_count_once(cell, tmp_path):
    """Heartbeats that pile up behind a slow call of their session (a take_control waiting for the station's lock)
    reach the station once, not once each: a backlog of them would keep a hold-to-run jog going after the page
    stopped beating (issue 21, hold-to-run). Counted by the station's heartbeat calls, not by time."""
    from server.app import create_app

    made, calls = [], []

    def factory():
        made.append(live.StationOnCell(cell, tmp_path / "station.sqlite3"))
        return made[-1]

    app = create_app(station_factory=factory, token=TOKEN)
    with live.serve(app) as url:
        station = made[0].station
        heartbeat = station.heartbeat
        station.heartbeat = lambda source=None: calls.append(source) or heartbeat(source=source)
        with connect(url.replace("http://", "ws://") + f"/ws?token={TOKEN}&controller=pad", open_timeout=10) as ws:
            assert json.loads(ws.recv(timeout=5))["type"] == "hello"
            _next(ws, "calibration")
            with station._lock:  # take_control waits for the lock on its worker thread; the heartbeats queue behind it
                ws.send(json.dumps({"type": "command", "name": "take_control"}))
                for _ in range(10):
                    ws.send(json.dumps({"type": "heartbeat"}))
                live.wait_for(lambda: sum(c.queued_heartbeats for c in app.state.hub.clients) == 10, 10.0)
            live.wait_for(lambda: station.controller == "pad", 10.0)
            ws.send(json.dumps({"type": "command", "name": "release_control"}))  # after the heartbeats: they were handled
            live.wait_for(lambda: station.controller is None, 10.0)
    assert calls == ["pad"], calls
