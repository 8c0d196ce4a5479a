"""POST /api/arm/step over HTTP (issue 9, item 2): a -Z step from home moves the gripper 10 mm down with
its wrist, pitch and yaw kept (FK of the measured joints); a step that cannot keep them is a 422 with the
reason, a step while the arm moves a 409, malformed bodies 422; nothing moves when refused."""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import live
from armlab.kinematics import load_arm

TOKEN = "step-token"
PAGE = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
ARM = load_arm("rx200")

cell, url = live.module_fixtures(seed=19, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


def gripper(cell) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(cell.arm.read_joint_state().position_rad, float)
    return ARM.fk(q), q


def test_z_step_from_home_keeps_the_gripper_turned_as_it_was(url, cell):
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        assert http.post("/api/arm/home", params={"wait": "true"}).status_code == 200
        T0, q0 = gripper(cell)
        for _ in range(2):
            reply = http.post("/api/arm/step", json={"axis": "z", "distance_m": -0.01}, params={"wait": "true"})
            assert reply.status_code == 200, reply.text
        T1, q1 = gripper(cell)
    assert abs(q1[4] - q0[4]) < math.radians(0.5), "wrist_rotate turned"
    assert np.abs(T1[:3, :3] - T0[:3, :3]).max() < math.radians(0.5), "the gripper turned"
    assert (T1[:3, 3] - T0[:3, 3]) == pytest.approx([0.0, 0.0, -0.02], abs=0.001)
    pose = reply.json()["gripper_pose"]
    assert abs(math.remainder(pose["yaw_rad"] - math.pi, 2 * math.pi)) < math.radians(0.5)


def test_refused_steps_say_why_and_move_nothing(url, cell):
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        assert http.post("/api/arm/home", params={"wait": "true"}).status_code == 200
        _, q0 = gripper(cell)
        too_far = http.post("/api/arm/step", json={"axis": "pitch", "angle_rad": 0.7})  # stretched out level: no reach left
        assert too_far.status_code == 422 and "out of reach" in too_far.json()["error"]["message"], too_far.text
        for body in (
            {"axis": "z", "angle_rad": 0.1},
            {"axis": "pitch", "distance_m": 0.01},
            {"axis": "z", "distance_m": 0.0},
            {"axis": "z", "distance_m": 0.5},
            {"axis": "roll", "angle_rad": 0.1, "speed_percent": 5},
            {"axis": "yaw", "angle_rad": 0.1},
        ):
            reply = http.post("/api/arm/step", json=body)
            assert reply.status_code == 422 and reply.json()["error"]["code"] == "invalid", body
        assert np.abs(gripper(cell)[1] - q0).max() < 2e-3
        assert http.post("/api/arm/joints", json={"q_rad": [0.4, 0, 0, 0, 0], "moving_time_s": 2.0}).status_code == 200
        busy = http.post("/api/arm/step", json={"axis": "pitch", "angle_rad": 0.1})
        assert busy.status_code == 409 and "still moving" in busy.json()["error"]["message"]
        live.wait_for(lambda: not cell.arm.is_moving(), 10)


def test_rotation_steps_and_speed_override(url, cell):
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        assert http.post("/api/arm/joints", json={"q_rad": list(ARM.ik([0.0, 0.25, 0.1], pitch=math.pi / 2))},
                         params={"wait": "true"}).status_code == 200
        T0, q0 = gripper(cell)
        assert http.post("/api/arm/step", json={"axis": "roll", "angle_rad": 0.3, "speed_percent": 50},
                         params={"wait": "true"}).status_code == 200
        T1, q1 = gripper(cell)
        assert abs(q1[4] - q0[4] - 0.3) < math.radians(0.5)
        assert np.linalg.norm(T1[:3, 3] - T0[:3, 3]) < 0.001
        assert http.post("/api/arm/step", json={"axis": "pitch", "angle_rad": -0.2}, params={"wait": "true"}).status_code == 200
        T2, _ = gripper(cell)
        assert math.asin(-T2[2, 0]) == pytest.approx(math.asin(-T1[2, 0]) - 0.2, abs=math.radians(0.5))
        assert np.linalg.norm(T2[:3, 3] - T1[:3, 3]) < 0.001


def test_the_python_client_steps_and_reports_refusals(url, cell):
    from armlab.client.station_client import StationClient, StationError

    httpx.post(url + "/api/control/release", headers=PAGE, timeout=10)  # the client commands as 'api'
    with StationClient(url, token=TOKEN) as client:
        client.home()
        T0, _ = gripper(cell)
        client.jog_step("y", 0.02, speed_percent=50)
        T1, _ = gripper(cell)
        assert (T1[:3, 3] - T0[:3, 3]) == pytest.approx([0.0, 0.02, 0.0], abs=0.001)
        with pytest.raises(StationError) as refused:
            client.jog_step("pitch", 0.7)  # stretched out level: no reach left to tilt down about the point
        assert refused.value.status_code == 422 and "out of reach" in str(refused.value)
