"""'holding' in the page is the gripper's evidence (issue 21, Misleading 2): fingers halted half way by an E-STOP
while closing on nothing are driven closed and stopped short of fully closed, but nothing resists them. The
page's gripper readout says empty, as the simulation's truth (holding_id None) and the status the jobs read."""

from __future__ import annotations

import pytest

from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

OPEN_WIDTH_M = 0.062
CLOSED_WIDTH_M = 0.018


def halt_fingers_mid_stroke(server, tries: int = 3) -> dict:
    """Close on nothing and E-STOP at once; returns the truth's gripper once the fingers halted half way."""
    for _ in range(tries):
        ready_idle(server)
        server.post("/api/gripper?wait=true", {"action": "release"})
        server.post("/api/gripper?wait=false", {"action": "grasp"})
        server.post("/api/estop")
        server.wait_status(lambda s: s["state"] == "estop", 10.0, "estop")
        gripper = server.get("/api/sim/truth")["gripper"]
        if CLOSED_WIDTH_M + 0.008 < gripper["width_m"] < OPEN_WIDTH_M - 0.008:
            return gripper
    raise AssertionError(f"the fingers never halted half way in {tries} tries: {gripper}")


def test_fingers_halted_on_nothing_read_empty_in_the_page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        truth = halt_fingers_mid_stroke(server)
        assert truth["holding_id"] is None
        status = server.wait_status(lambda s: s["state"] == "estop" and not s["moving"], 10.0, "the e-stopped station")
        page.wait_for_function("document.getElementById('pose-readout').textContent.includes('width')", timeout=10_000)
        readout = page.text_content("#pose-readout")
        width_mm = float(readout.split("width ")[1].split(" mm")[0])
        assert abs(width_mm - 1000 * truth["width_m"]) < 3, (readout, truth)  # the page shows the halted fingers
        assert status["gripper"]["holding"] is False, status["gripper"]
        assert page.get_attribute("#pose-readout", "data-holding") == "false", readout
        assert "empty" in readout and "holding" not in readout, readout
        assert page.errors == []
    finally:
        page.close()
        ready_idle(server)
        server.post("/api/gripper?wait=true", {"action": "release"})
