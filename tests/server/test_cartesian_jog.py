"""Hold-to-run Cartesian jog over REST and the websocket (issue 21, "What a pendant user reaches for"), on the
real-time simulated station behind a real server, ground truth from the simulation (the gripper point's recorded
path, the simulated joints): a held jog moves the gripper point along its world axis, off the axis by little, with
its pitch and yaw kept; after the last heartbeat, a jog_stop message or a dropped websocket it comes to rest within
what the deadman allows: v·(event window + one control period + jog_hold_s) + v²/2a (+ the servos' lag), measured
on simulation time; bad input and a client without the lease get a clear 4xx and nothing moves; held down into the
board it stops above it and says why. No wall-clock figures asserted (bench/cartesian_jog.py prints them)."""

from __future__ import annotations

import json
import math
import socket

import httpx
import numpy as np
import pytest
from websockets.sync.client import connect

import live
from armlab.devices.sim.config import load_sim_config
from armlab.kinematics import load_arm
from armlab.motion.gripper_step import angle_difference_rad, gripper_pose
from armlab.motion_config import load_motion_config

TOKEN = "cartesian-jog-token"
PAGE = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
START_M = [0.0, 0.25, 0.12]  # over the board, the gripper pointing straight down: every axis is open both ways
ARM = load_arm("rx200")
MOTION = load_motion_config()
CONTROL_PERIOD_S = load_sim_config().physics.control_period_s
OFF_AXIS_TOL_M = 0.002  # the measured gripper point off the jog's line (the servos' tracking included)
ANGLE_TOL_RAD = math.radians(0.6)
LAG_M = 0.003  # the simulated servos trail the command a little and catch up after the stop
HELD_SIM_S = 0.6
FINGER_GEOMS = {"palm", "left_finger_link", "right_finger_link", "left_pad", "right_pad"}

cell, url = live.module_fixtures(seed=41, token=TOKEN)


def _truth(cell) -> tuple[float, np.ndarray, np.ndarray]:
    """(sim time, gripper point, joints) of the simulation."""
    return cell.sim_time_s, cell.gripper_point_m(), np.asarray(cell.arm.read_joint_state().position_rad, float)


def _to_start(http: httpx.Client) -> None:
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 15)
    reply = http.post("/api/arm/pose", json={"position_m": START_M, "pitch_rad": math.pi / 2, "yaw_rad": 0.0}, params={"wait": "true"})
    assert reply.status_code == 200, reply.text
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 15)


def _stop_bound_m(v_m_s: float, window_s: float, hold_s: float = MOTION.jog_hold_s) -> float:
    """How far the gripper may still go after the last truth read before an event: at speed through the event's
    window, one control period and the hold, then braking at the jog's acceleration, plus the servos' lag. A stop
    the station was told of (a jog_stop answered within the window) holds the speed only until its re-plan takes
    over, handover_lead_s later, instead of the hold."""
    return v_m_s * (window_s + CONTROL_PERIOD_S + hold_s) + v_m_s**2 / (2 * MOTION.jog_accel_m_s2) + LAG_M


def _hold(cell, beat, seconds: float) -> None:
    """Beat (see live.held_down) for `seconds` of simulation time."""
    with live.held_down(beat):
        live.wait_sim(cell, seconds)


def _check_held_and_stopped(cell, axis: str, sign: int, v_m_s: float, start, before, after_event, what: str,
                            hold_s: float = MOTION.jog_hold_s) -> None:
    """The path since `start`: along the axis within the off-axis tolerance, pitch and yaw kept; after the event
    (truth `before` read just before it, `after_event` just after) at rest within the deadman's bound."""
    at_rest_by_s = after_event[0] + MOTION.jog_hold_s + CONTROL_PERIOD_S + v_m_s / MOTION.jog_accel_m_s2 + 0.05
    live.wait_for(lambda: not cell.arm.is_moving() and cell.sim_time_s > at_rest_by_s + 0.2, 10, 0.01)
    path = cell.stop_path_recording()
    stopped = _truth(cell)
    direction = np.zeros(3)
    direction["xyz".index(axis)] = sign
    offsets = path[:, 1:] - start[1]
    along = offsets @ direction
    off_axis = np.linalg.norm(offsets - along[:, None] * direction[None, :], axis=1)
    assert off_axis.max() < OFF_AXIS_TOL_M, f"{what}: the gripper point left the {axis} line by {off_axis.max() * 1000:.2f} mm"
    assert along[-1] > 0.5 * v_m_s * HELD_SIM_S, f"{what}: held {HELD_SIM_S} s at {v_m_s} m/s, moved {along[-1] * 1000:.1f} mm"
    pose0, pose1 = gripper_pose(ARM, start[2]), gripper_pose(ARM, stopped[2])
    assert abs(angle_difference_rad(pose1.pitch_rad, pose0.pitch_rad)) < ANGLE_TOL_RAD, f"{what}: the pitch changed"
    assert abs(angle_difference_rad(pose1.yaw_rad, pose0.yaw_rad)) < ANGLE_TOL_RAD, f"{what}: the yaw changed"
    travel_m = float((stopped[1] - before[1]) @ direction)
    bound_m = _stop_bound_m(v_m_s, after_event[0] - before[0], hold_s)
    print(f"{what}: {v_m_s:.3f} m/s, travelled {travel_m * 1000:.1f} mm after the event, bound {bound_m * 1000:.1f} mm")
    assert travel_m <= bound_m, f"{what}: travelled {travel_m * 1000:.1f} mm after the event, bound {bound_m * 1000:.1f} mm"
    later = path[path[:, 0] >= at_rest_by_s]
    assert len(later) and np.abs(later[:, 1:] - stopped[1]).max() < 5e-4, f"{what}: still moving after the deadman's time"


@pytest.mark.parametrize("axis, sign, percent", [("x", 1, 100), ("y", -1, 50), ("z", 1, 25)])
def test_a_held_rest_jog_moves_along_its_axis_and_stops_after_the_last_heartbeat(url, cell, axis, sign, percent):
    v_m_s = MOTION.jog_max_speed_m_s * percent / 100
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        _to_start(http)
        cell.start_path_recording(period_s=0.01)
        start = _truth(cell)
        reply = http.post("/api/arm/jog/cartesian", json={"axis": axis, "velocity_m_s": sign * MOTION.jog_max_speed_m_s,
                                                           "speed_percent": percent})
        assert reply.status_code == 200, reply.text
        _hold(cell, lambda: http.post("/api/heartbeat"), HELD_SIM_S)
        assert cell.arm.is_moving(), "the jog ended while heartbeats arrived"
        before = _truth(cell)
        assert http.post("/api/heartbeat").status_code == 200  # the last one
        after_event = _truth(cell)
        _check_held_and_stopped(cell, axis, sign, v_m_s, start, before, after_event, f"REST {axis}{sign:+} at {percent} %")


@pytest.mark.parametrize("how", ["stop message", "dropped websocket", "heartbeats stop"])
def test_a_websocket_jog_runs_while_held_and_stops_on_release(url, cell, how):
    v_m_s = MOTION.jog_max_speed_m_s
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        _to_start(http)
        with connect(url.replace("http://", "ws://") + f"/ws?token={TOKEN}&controller=pad", compression=None, max_size=None, max_queue=None,
                     open_timeout=10) as ws:
            assert json.loads(ws.recv(timeout=5))["type"] == "hello"
            cell.start_path_recording(period_s=0.01)
            start = _truth(cell)
            ws.send(json.dumps({"type": "jog_cartesian", "id": 7, "axis": "x", "velocity_m_s": -v_m_s}))
            assert _reply(ws, 7) == {"type": "jog_reply", "id": 7, "ok": True, "status_code": 200, "code": None, "message": None}
            _hold(cell, lambda: ws.send(json.dumps({"type": "heartbeat"})), HELD_SIM_S)
            assert cell.arm.is_moving(), "the jog ended while heartbeats arrived"
            before = _truth(cell)
            if how == "stop message":
                ws.send(json.dumps({"type": "jog_stop", "id": 8}))
                assert _reply(ws, 8)["ok"]
            elif how == "dropped websocket":  # the connection is cut (no closing handshake): the server reads its end
                ws.socket.shutdown(socket.SHUT_RDWR)
            after_event = _truth(cell)
            hold_s = MOTION.handover_lead_s if how == "stop message" else MOTION.jog_hold_s
            _check_held_and_stopped(cell, "x", -1, v_m_s, start, before, after_event, f"websocket, {how}", hold_s)  # connected


def _reply(ws, message_id: int) -> dict:
    """The jog_reply of the websocket message `message_id` (other messages skipped)."""
    for _ in range(500):
        message = ws.recv(timeout=10)
        if isinstance(message, str) and (parsed := json.loads(message)).get("type") == "jog_reply" and parsed["id"] == message_id:
            return parsed
    raise AssertionError(f"no jog_reply {message_id}")


BAD_BODIES = [
    ({"axis": "x", "velocity_m_s": "fast"}, "text"),
    ({"axis": "w", "velocity_m_s": 0.05}, "unknown axis"),
    ({"axis": "x", "velocity_m_s": 0.05, "speed_percent": 0}, "speed 0"),
    ({"axis": "x", "velocity_m_s": 0.05, "speed_percent": 101}, "speed 101"),
    ({"axis": "x", "velocity_m_s": 0.3}, "faster than jog_max_speed_m_s"),
    ({"axis": "x"}, "no velocity"),
]


def test_bad_jogs_are_refused_with_a_clear_4xx_and_nothing_moves(url, cell):
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        _to_start(http)
        _, point, _ = _truth(cell)
        raw = '{"axis": "x", "velocity_m_s": NaN}'  # what JSON.stringify never sends, a script might
        reply = http.post("/api/arm/jog/cartesian", content=raw, headers={"Content-Type": "application/json"})
        assert reply.status_code == 422 and reply.json()["error"]["code"] == "invalid", reply.text
        for body, what in BAD_BODIES:
            reply = http.post("/api/arm/jog/cartesian", json=body)
            assert reply.status_code == 422, (what, reply.text)
            assert reply.json()["error"]["message"], what
        no_token = httpx.post(url + "/api/arm/jog/cartesian", json={"axis": "x", "velocity_m_s": 0.05}, timeout=30)
        assert no_token.status_code == 401, no_token.text
        with connect(url.replace("http://", "ws://") + f"/ws?token={TOKEN}&controller=pad", compression=None, max_size=None,
                     open_timeout=10) as ws:
            ws.recv(timeout=5)
            for index, (body, what) in enumerate([({"axis": "x", "velocity_m_s": "NaN"}, "text NaN"), *BAD_BODIES]):
                ws.send(json.dumps({"type": "jog_cartesian", "id": index, **body}))
                reply = _reply(ws, index)
                assert not reply["ok"] and reply["status_code"] == 422 and reply["message"], (what, reply)
            ws.send('{"type": "jog_cartesian", "id": 50, "axis": "x", "velocity_m_s": NaN}')
            assert _reply(ws, 50)["status_code"] == 422
            ws.send(json.dumps({"type": "jog", "id": 51, "velocity_rad_s": [0.3, 0, 0, 0, 0], "speed_percent": 0}))
            assert _reply(ws, 51)["status_code"] == 422
            # Another controller holds the lease: the same jog is refused (409 not_controller) over both.
            assert http.post("/api/control/take", headers={**PAGE, "X-Armlab-Controller": "other"}).status_code == 200
            try:
                reply = http.post("/api/arm/jog/cartesian", json={"axis": "x", "velocity_m_s": 0.05})
                assert reply.status_code == 409 and reply.json()["error"]["code"] == "not_controller", reply.text
                ws.send(json.dumps({"type": "jog_cartesian", "id": 52, "axis": "x", "velocity_m_s": 0.05}))
                assert _reply(ws, 52)["code"] == "not_controller"
            finally:
                assert http.post("/api/control/take").status_code == 200
        with connect(url.replace("http://", "ws://") + "/ws", compression=None, max_size=None, open_timeout=10) as viewer:
            viewer.recv(timeout=5)  # a view-only session (no token)
            viewer.send(json.dumps({"type": "jog_cartesian", "id": 53, "axis": "x", "velocity_m_s": 0.05}))
            assert _reply(viewer, 53)["status_code"] == 401
        live.wait_sim(cell, 0.3)
        assert not cell.arm.is_moving()
        assert np.abs(cell.gripper_point_m() - point).max() < 5e-4, "a refused jog moved the arm"


def test_a_jog_into_the_board_stops_above_it_and_says_why(url, cell):
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        _to_start(http)
        with httpx.Client(base_url=url, timeout=30, headers=PAGE) as beats, live.held_down(lambda: beats.post("/api/heartbeat")):
            assert http.post("/api/arm/jog/cartesian", json={"axis": "z", "velocity_m_s": -MOTION.jog_max_speed_m_s}).status_code == 200
            live.wait_for(cell.arm.is_moving, 10, 0.005)
            assert live.wait_for(lambda: not cell.arm.is_moving(), 60, 0.02), "the jog down never stopped"
        live.wait_sim(cell, 0.3)
        _, point, q = _truth(cell)
        assert cell.contact_depth_at_mm(q, FINGER_GEOMS) == 0.0, "the fingers touch the board"
        assert point[2] < START_M[2] - 0.08, f"stopped at z = {point[2] * 1000:.1f} mm, far above the board"
        refused = http.post("/api/arm/jog/cartesian", json={"axis": "z", "velocity_m_s": -0.05})
        assert refused.status_code == 422 and "board" in refused.json()["error"]["message"], refused.text
        events = http.get("/api/history/events", params={"text": "stops short"}).json()["data"]
        assert events and "board" in events[0]["message"], events
        assert np.abs(cell.gripper_point_m() - point).max() < 5e-4, "the refused jog moved the arm"
        assert http.post("/api/arm/jog/cartesian", json={"axis": "z", "velocity_m_s": 0.05}).status_code == 200  # up is open
