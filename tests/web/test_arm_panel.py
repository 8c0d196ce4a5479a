"""The Arm panel, the event log and the joint plot (issue 9 items 4 and 5): the torque button shows the
motors' state and asks before letting a raised arm fall, the fall is reported as motion; manual commands
get a log line after a job too; a cancel is logged once; the plot's y range comes from the joint limits
and its legend is visible."""

from __future__ import annotations

import math

import pytest

from browser_helpers import in_view_and_on_top, open_page, teach_program, wait_frames

pytestmark = pytest.mark.browser

# Raised and pointing away from the blocks (they lie in y > 0): waist near -180° points the arm along -y.
RAISED_AWAY_RAD = [-2.5, 0.0, 0.0, 0.0, 0.0]


@pytest.fixture()
def page(browser, server):
    if server.get("/api/status")["state"] in ("estop", "fault"):
        server.post("/api/reset")
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    wait_frames(page, 2)
    page.wait_for_function("window.armlab.status && window.armlab.connected")
    yield page
    page.close()


def test_torque_button_shows_state_and_asks_before_the_arm_falls(page, server):
    server.post("/api/arm/joints?wait=true", {"q_rad": RAISED_AWAY_RAD, "moving_time_s": 2.0})
    server.wait_status(lambda s: not s["moving"], 10.0, "the arm raised and still")
    page.wait_for_function("!document.getElementById('btn-torque').disabled")
    button = page.locator("#btn-torque")
    assert "on" in button.text_content().lower() and "off" not in button.text_content().lower()

    button.click()  # asks first; Cancel leaves the torque on and the arm where it is
    page.wait_for_selector("#confirm-dialog[open]", timeout=3_000)
    assert "fall" in page.text_content("#confirm-dialog")
    page.click("#confirm-cancel")
    page.wait_for_selector("#confirm-dialog", state="hidden")
    status = server.get("/api/status")
    assert status["torque_enabled"] is True and not status["moving"]
    z_raised_m = status["gripper_pose"]["position_m"][2]

    button.click()
    page.wait_for_selector("#confirm-dialog[open]", timeout=3_000)
    page.click("#confirm-ok")
    server.wait_status(lambda s: s["torque_enabled"] is False, 5.0, "torque off")
    page.wait_for_function("document.getElementById('btn-torque').textContent.includes('OFF')", timeout=5_000)
    # The limp arm falls: the page reports the motion (from the station's measured velocity).
    page.wait_for_function("document.getElementById('status-detail').textContent.includes('moving')", timeout=5_000)
    settled = server.wait_status(lambda s: not s["moving"], 20.0, "the fallen arm at rest")
    assert settled["gripper_pose"]["position_m"][2] < z_raised_m - 0.1

    button.click()  # torque on needs no question
    server.wait_status(lambda s: s["torque_enabled"] is True, 5.0, "torque on")
    assert page.locator("#confirm-dialog[open]").count() == 0
    page.wait_for_function("document.getElementById('btn-torque').textContent.includes('on')", timeout=5_000)
    server.post("/api/arm/home?wait=true", {"moving_time_s": 2.0})
    assert page.errors == []
