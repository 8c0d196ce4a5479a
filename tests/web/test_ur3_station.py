"""The station on the UR3 suction workcell (`armlab serve --workcell ur3_suction`) is arm-agnostic: the
websocket hello and GET /api/arm carry the UR3's six joints and limits (compared with config/arms/ur3.yaml
read here), the page builds six jog sliders and readout rows from them and its sixth slider moves the
sixth joint, a Cartesian jog step from the page keeps the tool's whole orientation (FK of the measured
joints before and after, with the workcell's kinematics model), and the Interbotix facade refuses the
UR3 with a clear error while nothing moves. Real server subprocess, real Chromium, real websockets."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import yaml
from browser_helpers import REPO, open_page, ready_idle, wait_frames
from websockets.sync.client import connect

from armlab.client import InterbotixManipulatorXS, NotInterbotixArm
from armlab.workcell import load_workcell_arm

pytestmark = pytest.mark.browser

ARM_FILE = yaml.safe_load((REPO / "config/arms/ur3.yaml").read_text())
WORKCELL_FILE = yaml.safe_load((REPO / "config/workcells/ur3_suction.yaml").read_text())
NAMES = ARM_FILE["joint_names"]
LIMITS_RAD = [[math.radians(lo), math.radians(hi)] for lo, hi in zip(ARM_FILE["limits"]["lower_deg"], ARM_FILE["limits"]["upper_deg"])]


@pytest.fixture(scope="module")
def model():
    return load_workcell_arm("ur3_suction")


def _over_the_board(server, model, position_m=(0.05, 0.30, 0.15), pitch_rad=math.pi / 2) -> dict:
    """The cup over the board (a joint move there), pointing down at pitch_rad below the horizontal, settled."""
    q_now = np.asarray(server.get("/api/status")["joints_rad"])
    q = model.ik(list(position_m), pitch=pitch_rad, yaw=0.0, q_seed=q_now)
    server.post("/api/arm/joints?wait=true", {"q_rad": q.tolist(), "moving_time_s": 2.0})
    return server.wait_status(lambda s: s["state"] == "idle" and not s["moving"], 15.0, "the UR3 over the board")


def test_hello_and_api_arm_carry_the_ur3_joints_and_limits(ur3_server):
    with connect(ur3_server.base_url.replace("http://", "ws://") + f"/ws?token={ur3_server.token}", open_timeout=10) as ws:
        hello = json.loads(ws.recv(timeout=10))
    assert hello["type"] == "hello"
    for arm in (hello["arm"], ur3_server.get("/api/arm")):
        assert arm["name"] == "ur3" and arm["joint_names"] == NAMES and len(NAMES) == 6
        assert np.allclose(arm["joint_limits_rad"], LIMITS_RAD)
        assert arm["gripper_type"] == WORKCELL_FILE["gripper"]["type"] == "suction"
        assert arm["full_pose"] is True and arm["vendor"] != "interbotix"
    assert hello["workcell"]["name"] == "ur3_suction"  # the board the page draws is the UR3's


def test_the_page_builds_six_sliders_and_the_sixth_moves_the_sixth_joint(ur3_server, browser, model):
    ready_idle(ur3_server)
    _over_the_board(ur3_server, model)
    page = open_page(browser, f"{ur3_server.base_url}/?token={ur3_server.token}")
    try:
        wait_frames(page, 1)
        page.wait_for_function("document.querySelectorAll('#joint-sliders input[type=range]').length === 6", timeout=15_000)
        sliders = page.eval_on_selector_all(
            "#joint-sliders input[type=range]", "els => els.map(e => ({id: e.id, min: Number(e.min), max: Number(e.max)}))")
        assert [s["id"] for s in sliders] == [f"slider-{name}" for name in NAMES]
        assert np.allclose([[s["min"], s["max"]] for s in sliders], np.degrees(LIMITS_RAD))
        page.wait_for_function("document.querySelectorAll('#joint-readout tr').length === 6")
        assert page.eval_on_selector_all("#joint-readout tr", "rows => rows.map(r => r.cells[0].textContent)") == NAMES
        assert page.text_content("#btn-close") == "Vacuum on" and page.text_content("#btn-open") == "Vacuum off"
        page.wait_for_function("document.getElementById('pose-readout').textContent.includes('vacuum off')")
        assert "width" not in page.text_content("#pose-readout")  # a cup has no grasp width

        page.wait_for_function("window.armlab.status && !document.getElementById('btn-send-joints').disabled", timeout=10_000)
        q_before = np.asarray(ur3_server.get("/api/status")["joints_rad"])
        target_deg = math.degrees(q_before[5]) + 20.0
        page.eval_on_selector(  # as a drag ends: value, then the change event the page sends on
            f"#slider-{NAMES[5]}", "(el, v) => { el.value = v; el.dispatchEvent(new Event('input')); el.dispatchEvent(new Event('change')); }",
            target_deg)
        moved = ur3_server.wait_status(
            lambda s: not s["moving"] and abs(math.degrees(s["joints_rad"][5]) - target_deg) < 0.5, 15.0, f"{NAMES[5]} at the slider's angle")
        assert np.allclose(np.asarray(moved["joints_rad"])[:5], q_before[:5], atol=math.radians(0.5))  # only the sixth joint
        assert page.errors == []
    finally:
        page.close()


def test_a_cartesian_jog_step_from_the_page_keeps_the_tool_orientation(ur3_server, browser, model):
    ready_idle(ur3_server)
    start = _over_the_board(ur3_server, model, pitch_rad=1.2)  # tilted: a pitch-and-yaw step would turn the cup's heading
    page = open_page(browser, f"{ur3_server.base_url}/?token={ur3_server.token}")
    try:
        page.wait_for_function("!document.querySelector(\"[data-jog='x+']\").disabled", timeout=15_000)
        T0 = model.fk(np.asarray(start["joints_rad"]))
        page.select_option("#jog-step", "0.025")
        page.click("[data-jog='x+']")
        end = ur3_server.wait_status(lambda s: not s["moving"] and model.fk(np.asarray(s["joints_rad"]))[0, 3] > T0[0, 3] + 0.02,
                                     15.0, "the x step to end")
        T1 = model.fk(np.asarray(end["joints_rad"]))
        turn_deg = math.degrees(math.acos(np.clip((np.trace(T0[:3, :3].T @ T1[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)))
        assert turn_deg < 0.3, f"the tool turned {turn_deg:.2f}° during an x step"
        assert T1[0, 3] - T0[0, 3] == pytest.approx(0.025, abs=0.002)
        assert abs(T1[1, 3] - T0[1, 3]) < 0.002 and abs(T1[2, 3] - T0[2, 3]) < 0.002
        assert page.errors == []
    finally:
        page.close()


def test_the_interbotix_facade_refuses_the_ur3_and_nothing_moves(ur3_server):
    ready_idle(ur3_server)
    q_before = ur3_server.get("/api/status")["joints_rad"]
    with pytest.raises(NotInterbotixArm, match=r"ur3.*universal_robots.*StationClient"):
        InterbotixManipulatorXS("rx200", "arm", "gripper", url=ur3_server.base_url, token=ur3_server.token)
    status = ur3_server.get("/api/status")
    assert not status["moving"] and np.allclose(status["joints_rad"], q_before, atol=1e-3)


def test_a_pose_move_over_rest_keeps_the_cup_heading_and_points_down(ur3_server, model):
    ready_idle(ur3_server)
    start = _over_the_board(ur3_server, model)
    T0 = model.fk(np.asarray(start["joints_rad"]))
    target = [-0.12, 0.36, 0.12]
    ur3_server.post("/api/arm/pose?wait=true", {"position_m": target, "moving_time_s": 2.0})
    end = ur3_server.wait_status(lambda s: s["state"] == "idle" and not s["moving"], 15.0, "the pose move to end")
    T1 = model.fk(np.asarray(end["joints_rad"]))
    assert np.linalg.norm(T1[:3, 3] - target) < 0.002
    assert math.degrees(math.acos(np.clip(-T1[2, 0], -1.0, 1.0))) < 0.5  # the cup's axis straight down
    heading = [math.degrees(math.atan2(T[1, 1], T[0, 1])) for T in (T0, T1)]
    assert abs(math.remainder(heading[1] - heading[0], 360.0)) < 0.5, heading
