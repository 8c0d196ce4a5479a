"""Keyboard jogging (issue 9 item 2, page side): PageDown steps the gripper down, an arrow key along x, Shift+arrow
turns the pitch; each through POST /api/arm/step, the gripper keeping its orientation on the straight steps."""

from __future__ import annotations

import math

import pytest

from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

STEP_M = 0.01  # the panel's default step


def settled_pose(server) -> dict:
    return server.wait_status(lambda s: not s["moving"] and s["state"] == "idle", 20.0, "the arm still")["gripper_pose"]


def press_and_wait_answer(page, key: str) -> None:
    """Press `key` and wait for the page's log line of its step ('jog …: ok'); a refusal fails with its message."""
    page.evaluate("window.armlab.log.clear()")
    page.keyboard.press(key)
    page.wait_for_function("document.querySelectorAll('#event-log li').length > 0", timeout=10_000)
    line = page.text_content("#event-log li")
    assert ": ok" in line, f"{key}: {line}"


def test_keys_step_the_gripper(browser, server):
    ready_idle(server)
    server.post("/api/arm/joints?wait=true", {"q_rad": [0.0, 0.0, 0.3, 0.9, 0.0], "moving_time_s": 1.5})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("!document.querySelector(\"[data-jog='z-']\").disabled", timeout=10_000)
        page.click("#live")  # focus on the page, not a field
        for key, axis, sign in (("PageDown", 2, -1), ("ArrowRight", 0, 1), ("ArrowUp", 1, 1)):
            before = settled_pose(server)
            press_and_wait_answer(page, key)
            after = settled_pose(server)
            moved = [a - b for a, b in zip(after["position_m"], before["position_m"])]
            assert moved[axis] == pytest.approx(sign * STEP_M, abs=0.002), (key, moved)
            assert all(abs(m) < 0.002 for i, m in enumerate(moved) if i != axis), (key, moved)
            assert abs(after["pitch_rad"] - before["pitch_rad"]) < math.radians(0.5)
        before = settled_pose(server)
        press_and_wait_answer(page, "Shift+ArrowDown")  # pitch down 5°
        after = settled_pose(server)
        assert after["pitch_rad"] - before["pitch_rad"] == pytest.approx(math.radians(5), abs=math.radians(0.5))
        assert page.errors == []
    finally:
        page.close()
        server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})


def _truth_gripper_m(server) -> list[float]:
    server.wait_status(lambda s: not s["moving"] and s["state"] == "idle", 20.0, "the arm still")
    return server.get("/api/sim/truth")["gripper"]["position_m"]


def test_x_buttons_from_home_move_along_x(browser, server):
    """Issue 21: X jog from Home was always refused ('yaw would change by 3.50°'); the page's +X/−X buttons at
    25 mm from Home now move the gripper along x (the simulation's ground truth), each answered ok."""
    ready_idle(server)
    server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("!document.querySelector(\"[data-jog='x+']\").disabled", timeout=10_000)
        page.select_option("#jog-step", "0.025")
        for button, sign in (("x+", 1), ("x-", -1)):
            before = _truth_gripper_m(server)
            page.evaluate("window.armlab.log.clear()")
            page.click(f"[data-jog='{button}']")
            page.wait_for_function("[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes('jog x'))",
                                   timeout=10_000)
            lines = page.eval_on_selector_all("#event-log li", "els => els.map(e => e.textContent)")
            assert any("jog x" in line and ": ok" in line for line in lines), f"{button}: {lines}"
            assert any("yaw turned" in line for line in lines), lines  # the operator is told the heading followed the waist
            after = _truth_gripper_m(server)
            moved = [a - b for a, b in zip(after, before)]
            assert moved[0] == pytest.approx(sign * 0.025, abs=0.003) and abs(moved[1]) < 0.003 and abs(moved[2]) < 0.003, (button, moved)
        assert page.errors == []
    finally:
        page.close()
        server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
