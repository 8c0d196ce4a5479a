"""Typed targets are checked before they are sent (issue 21, "Type a target"): POST /api/arm/pose/check and
/api/arm/joints/check answer what the move would do (goal joints, duration, the gripper at the goal) or refuse
with the move's own reason, and move nothing, over real HTTP on the real-time simulation (ground truth: the
simulated joints). A check needs no control lease: a view-only page may ask."""

from __future__ import annotations

import httpx
import numpy as np
import pytest

import live

TOKEN = "check-token"
PAGE = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
START_RAD = [0.3, 0.0, 0.3, 0.9, 0.0]

cell, url = live.module_fixtures(seed=23, token=TOKEN)


@pytest.fixture(scope="module")
def http(url, cell):
    with httpx.Client(base_url=url, timeout=30) as client:
        client.post("/api/arm/joints", json={"q_rad": START_RAD, "moving_time_s": 1.0}, params={"wait": "true"}, headers=PAGE)
        live.wait_for(lambda: not cell.arm.is_moving(), 10, 0.01)
        yield client


def _truth_rad(cell) -> np.ndarray:
    return np.asarray(cell.arm.read_joint_state().position_rad, dtype=float)


def _checked(http, cell, path: str, body) -> httpx.Response:
    """POST a check; the arm must not have been commanded (joints unchanged, not moving)."""
    before = _truth_rad(cell)
    content = body if isinstance(body, str) else None
    response = http.post(path, json=None if content else body, content=content,
                         headers={"Content-Type": "application/json"} if content else None)
    assert not cell.arm.is_moving(), f"{path} {body}: the arm moves after a check"
    assert np.abs(_truth_rad(cell) - before).max() < 1e-3, f"{path} {body}: the joints changed"
    return response


def test_a_reachable_pose_is_answered_with_its_goal_and_nothing_moves(http, cell):
    target = [0.25, 0.05, 0.10]
    answer = _checked(http, cell, "/api/arm/pose/check", {"position_m": target, "pitch_rad": 1.5707963})
    assert answer.status_code == 200, answer.text
    body = answer.json()
    assert np.allclose(body["gripper_pose"]["position_m"], target, atol=1e-3), body
    assert len(body["q_rad"]) == 5 and body["duration_s"] > 0
    joints = _checked(http, cell, "/api/arm/joints/check", {"q_rad": body["q_rad"]})
    assert joints.status_code == 200 and np.allclose(joints.json()["gripper_pose"]["position_m"], target, atol=1e-3), joints.text


@pytest.mark.parametrize(("path", "body", "words"), [
    ("/api/arm/pose/check", {"position_m": [2.0, 0.0, 0.1]}, ["reach"]),
    ("/api/arm/pose/check", {"position_m": [0.25, 0.0, -0.05]}, ["below the table"]),
    ("/api/arm/pose/check", '{"position_m": [NaN, 0.0, 0.1]}', ["position_m"]),
    ("/api/arm/pose/check", {"position_m": ["abc", 0.0, 0.1]}, ["position_m"]),
    ("/api/arm/joints/check", {"q_rad": [0.0, 0.0, 0.0, 0.0]}, ["5"]),
    ("/api/arm/joints/check", {"q_rad": [0.0, 3.0, 0.0, 0.0, 0.0]}, ["shoulder"]),
])
def test_bad_targets_are_refused_with_the_reason_and_nothing_moves(http, cell, path, body, words):
    answer = _checked(http, cell, path, body)
    assert answer.status_code == 422, answer.text
    message = answer.json()["error"]["message"]
    assert all(word in message for word in words), message
