"""The reach state before a click (issue 21, Misleading 5, the UR3 part): on the UR3 with its suction cup, 'out of
reach' with the cup flat on top appeared only after a click. In Click-grab mode the point under the resting pointer
is now checked as the grab would plan it (POST /api/grab/check, nothing moves) and the view says, before any click,
that the spot is out of reach and what to do; over a block in reach it says what the click would grab. No click is
made: the simulated arm does not move."""

from __future__ import annotations

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from browser_helpers import canvas_point, enter_click_mode, open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

FAR_M = [0.40, 0.40, 0.0]  # out of the UR3's top-down reach (the grab answers 422 unreachable)


def test_the_reach_state_shows_before_a_click_on_the_ur3(browser, ur3_server):
    server = ur3_server
    ready_idle(server)
    server.post("/api/calibrate?wait=true", timeout_s=90.0)
    server.wait_status(lambda s: s["calibration_state"] == "trusted" and s["state"] == "idle", 60.0, "calibrated")
    server.wait_status(lambda s: server.get("/api/detections")["data"], 30.0, "blocks detected")
    refused = server.request("POST", "/api/grab/check", json={"position_m": FAR_M})
    assert refused.status_code == 422 and refused.json()["error"]["code"] == "unreachable", refused.text
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        enter_click_mode(page, "grab")
        before = server.get("/api/sim/truth")["gripper"]
        u, v = page.evaluate(
            """async (p) => { const { worldToCameraPx } = await import('/js/projection.js');
                const c = worldToCameraPx(p, window.armlab.live.cameraModel); return [c.u, c.v]; }""", FAR_M)
        page.mouse.move(*canvas_point(page, u, v))
        page.wait_for_function("document.getElementById('reach-state').dataset.ok === 'false'", timeout=60_000)
        text = page.text_content("#reach-state")
        assert "out of the arm's reach" in text and "click a spot" in text, text

        block = server.get("/api/detections")["data"][0]
        page.mouse.move(*canvas_point(page, *block["center_px"]))
        try:
            page.wait_for_function("document.getElementById('reach-state').dataset.ok === 'true'", timeout=60_000)
        except PlaywrightTimeout:  # say what the page showed instead
            raise AssertionError((page.text_content("#reach-state"), page.text_content("#hover-world"), block)) from None
        text = page.text_content("#reach-state")
        assert f"{block['color']} block" in text, (text, block)
        page.mouse.move(1, 1)  # leaving the view hides it
        page.wait_for_function("document.getElementById('reach-state').hidden", timeout=5_000)
        after = server.get("/api/sim/truth")["gripper"]
        assert after["position_m"] == pytest.approx(before["position_m"], abs=0.002)  # nothing moved: no click
        assert page.errors == []
    finally:
        page.close()
