"""Messages that say what the operator can do (issue 21, Misleading 5), in the page on the simulated RX200:
a click-grab beyond the arm's reach, or so far out that the fingers would touch the board, says so in the
operator's terms and says to click nearer the arm (before: the planner's 'gripper point at z = ... below the
board surface + clearance'); a cancelled job's score says it was cancelled and how many blocks were done (before:
'0 / 100 ... within the 180 s limit')."""

from __future__ import annotations

import pytest

from browser_helpers import canvas_point, enter_click_mode, open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

STARTUP_SCENE = {"event": "pick_sort", "level": 1, "seed": 3}  # conftest's SCENE_ARGS


def calibrated(server) -> None:
    if server.get("/api/status")["calibration_state"] != "trusted":
        ready_idle(server)
        server.post("/api/calibrate?wait=true", timeout_s=90.0)
        server.wait_status(lambda s: s["calibration_state"] == "trusted" and s["state"] == "idle", 60.0, "calibrated")


def page_point_of_world(page, world_m) -> tuple[float, float]:
    u, v = page.evaluate(
        """async (p) => { const { worldToCameraPx } = await import('/js/projection.js');
            const c = worldToCameraPx(p, window.armlab.live.cameraModel); return [c.u, c.v]; }""", world_m)
    return canvas_point(page, u, v)


def log_lines(page) -> list[str]:
    return page.eval_on_selector_all("#event-log li", "els => els.map(e => e.textContent)")


def wait_log(page, text: str, timeout_ms: int = 30_000) -> list[str]:
    page.wait_for_function(f"[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes({text!r}))",
                           timeout=timeout_ms)
    return [line for line in log_lines(page) if text in line]


def test_far_clicks_say_to_click_nearer_the_arm(browser, server):
    calibrated(server)
    ready_idle(server)
    server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        enter_click_mode(page, "grab")
        # beyond the reach: refused before anything moves
        before = server.get("/api/sim/truth")["gripper"]["position_m"]
        page.evaluate("window.armlab.log.clear()")
        page.mouse.click(*page_point_of_world(page, [0.40, 0.40, 0.0]))
        lines = wait_log(page, "nearer the arm")
        assert any("out of the arm's reach" in line for line in lines), lines
        assert not any("clearance (" in line or "wrist centre" in line for line in log_lines(page)), log_lines(page)
        after = server.get("/api/sim/truth")["gripper"]["position_m"]
        assert max(abs(a - b) for a, b in zip(before, after)) < 0.002, (before, after)

        # in reach but only tilted, where the fingers would touch the board on the way down
        ready_idle(server)
        page.evaluate("window.armlab.log.clear()")
        page.mouse.click(*page_point_of_world(page, [0.0, 0.45, 0.0]))
        lines = wait_log(page, "nearer the arm", 60_000)
        assert any("touch the board" in line for line in lines), lines
        assert not any("clearance (" in line for line in log_lines(page)), log_lines(page)
        assert page.errors == []
    finally:
        page.close()
        ready_idle(server)
        server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})


def test_a_cancelled_job_says_cancelled_and_what_was_done(browser, server):
    calibrated(server)
    ready_idle(server)
    server.post("/api/sim/scene", STARTUP_SCENE)
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("document.querySelectorAll('#comp-job option').length > 0", timeout=15_000)
        page.select_option("#comp-job", "pick_sort")
        page.select_option("#comp-level", "1")
        page.wait_for_function("!document.getElementById('btn-comp-start').disabled", timeout=15_000)
        page.click("#btn-comp-start")
        server.wait_status(lambda s: s["job"] and s["job"]["name"] == "pick_sort" and s["job"]["state"] == "running",
                           20.0, "the job running")
        page.wait_for_function("!document.getElementById('btn-comp-cancel').disabled", timeout=10_000)
        page.click("#btn-comp-cancel")
        job = server.wait_status(lambda s: s["job"]["state"] == "cancelled" and s["state"] == "idle", 90.0, "cancelled")["job"]
        page.wait_for_function("document.getElementById('comp-score-points').textContent.includes('/')", timeout=60_000)
        points = page.text_content("#comp-score-points")
        meta = page.text_content("#comp-score-meta")
        task = job["extra"]["task"]
        assert "cancelled" in points and "cancelled" in meta, (points, meta)
        assert "within the" not in meta, meta
        assert f"{task['done']} of {task['done'] + task['left']} blocks done" in meta, (meta, task)
        assert page.errors == []
    finally:
        page.close()
        ready_idle(server)
        server.post("/api/sim/scene", STARTUP_SCENE)
