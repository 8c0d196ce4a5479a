"""Type a target (issue 21, "What a pendant user reaches for"): x, y, z (mm), pitch and yaw (°), or every joint (°),
and Go. The page reads the fields strictly, has the station check the move (POST /api/arm/*/check) and only then
sends it; a refusal is shown next to the form with its reason. Ground truth from the simulation: a reachable target
is reached; text, NaN, an empty field, a target out of reach or a joint beyond its limit move nothing (the joints
unchanged, no move request sent)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from browser_helpers import page_with_the_arm_at, ready_idle

pytestmark = pytest.mark.browser

START_RAD = [0.3, 0.0, 0.3, 0.9, 0.0]


@pytest.fixture
def page(browser, server):
    page = page_with_the_arm_at(browser, server, START_RAD,
                                "!document.getElementById('btn-target-go').disabled && document.getElementById('target-joint-0')")
    page.moves = []
    page.on("request", lambda r: page.moves.append(r.url) if r.method == "POST" and r.url.endswith(("/api/arm/pose", "/api/arm/joints"))
            else None)
    yield page
    page.close()


def _truth(server) -> tuple[np.ndarray, np.ndarray]:
    t = server.get("/api/sim/truth")
    return np.asarray(t["arm"]["position_rad"]), np.asarray(t["gripper"]["position_m"])


def _fill_pose(page, x="", y="", z="", pitch="", yaw=""):
    for field, value in (("x", x), ("y", y), ("z", z), ("pitch", pitch), ("yaw", yaw)):
        page.fill(f"#target-{field}", value)


def _result(page, state: str) -> str:
    page.wait_for_function(f"document.getElementById('target-result').dataset.state === '{state}'", timeout=15_000)
    return page.text_content("#target-result")


def test_a_typed_reachable_pose_is_checked_then_reached(page, server):
    _fill_pose(page, x="250", y="-50", z="60", pitch="90")
    page.click("#btn-target-go")
    text = _result(page, "sent")
    assert "moving" in text, text
    server.wait_status(lambda s: not s["moving"], 20.0, "the arm to arrive")
    _, gripper_m = _truth(server)
    assert np.abs(gripper_m - [0.25, -0.05, 0.06]).max() < 0.004, gripper_m
    assert len(page.moves) == 1
    assert page.errors == []


def test_typed_joints_are_checked_then_reached(page, server):
    page.click("#btn-target-here")
    page.fill("#target-joint-0", "-20")
    page.click("#btn-joints-go")
    assert "moving" in _result(page, "sent")
    server.wait_status(lambda s: not s["moving"], 20.0, "the arm to arrive")
    q_rad, _ = _truth(server)
    assert q_rad[0] == pytest.approx(math.radians(-20), abs=0.01) and np.abs(q_rad[1:] - START_RAD[1:]).max() < 0.02, q_rad


@pytest.mark.parametrize(("fields", "says"), [
    ({"x": "abc", "y": "0", "z": "60"}, "x (mm): 'abc' is not a number"),
    ({"x": "NaN", "y": "0", "z": "60"}, "x (mm): 'NaN' is not a number"),
    ({"x": "250", "y": "0", "z": ""}, "z (mm): type a number"),
    ({"x": "250", "y": "0", "z": "60", "pitch": "1e400"}, "pitch (°): '1e400' is not a number"),
    ({"x": "2000", "y": "0", "z": "60"}, "reach"),
    ({"x": "250", "y": "0", "z": "-50"}, "below the table"),
])
def test_bad_typed_poses_are_refused_in_place_and_nothing_moves(page, server, fields, says):
    q_before, _ = _truth(server)
    _fill_pose(page, **fields)
    page.click("#btn-target-go")
    text = _result(page, "refused")
    assert says in text, text
    assert page.moves == [], f"a move was sent: {page.moves}"
    q_after, _ = _truth(server)
    assert np.abs(q_after - q_before).max() < 1e-3 and not server.get("/api/status")["moving"]
    assert page.errors == []


def test_a_joint_beyond_its_limit_is_refused_in_place_and_nothing_moves(page, server):
    q_before, _ = _truth(server)
    page.click("#btn-target-here")
    page.fill("#target-joint-1", "170")  # the shoulder's limit is far below
    page.click("#btn-joints-go")
    text = _result(page, "refused")
    assert "shoulder" in text, text
    assert page.moves == []
    q_after, _ = _truth(server)
    assert np.abs(q_after - q_before).max() < 1e-3
