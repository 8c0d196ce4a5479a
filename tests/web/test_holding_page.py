"""'holding' in the page is the gripper's evidence (issue 21, Misleading 2): fingers halted half way by an E-STOP
while closing on nothing are driven closed and stopped short of fully closed, but nothing resists them. The
page's gripper readout says empty, as the simulation's truth (holding_id None) and the status the jobs read."""

from __future__ import annotations

import time

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
        # E-STOP once the fingers are on their way (a press right after the command could beat their first step on
        # a quiet machine, or the closed fingers on a busy one): the truth's width leaving the open band.
        deadline = time.monotonic() + 10.0
        while server.get("/api/sim/truth")["gripper"]["width_m"] > OPEN_WIDTH_M - 0.010 and time.monotonic() < deadline:
            time.sleep(0.005)
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
        truth = server.get("/api/sim/truth")["gripper"]  # the fingers at rest (the first read may be mid-halt)
        assert CLOSED_WIDTH_M + 0.005 < truth["width_m"] < OPEN_WIDTH_M - 0.005, truth
        # The page shows the halted fingers (its readout follows the telemetry: wait for the newest value).
        shown = page.wait_for_function(
            """(width_mm) => { const m = /width ([\\d.]+) mm/.exec(document.getElementById('pose-readout').textContent);
                              return m && Math.abs(parseFloat(m[1]) - width_mm) < 3 ? m[1] : null; }""",
            arg=1000 * truth["width_m"], timeout=10_000)
        assert shown.json_value()
        readout = page.text_content("#pose-readout")
        assert status["gripper"]["holding"] is False, status["gripper"]
        assert page.get_attribute("#pose-readout", "data-holding") == "false", readout
        assert "empty" in readout and "holding" not in readout, readout
        assert page.errors == []
    finally:
        page.close()
        ready_idle(server)
        server.post("/api/gripper?wait=true", {"action": "release"})
