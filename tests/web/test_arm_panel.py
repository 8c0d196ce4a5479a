"""The Arm panel, the event log and the joint plot (issue 9 items 4 and 5): the torque button shows the
motors' state and asks before letting a raised arm fall, the fall is reported as motion; manual commands
get a log line after a job too; a cancel is logged once; the plot's y range comes from the joint limits
and its legend is visible."""

from __future__ import annotations

import math

import pytest

from browser_helpers import in_view_and_on_top, open_page, ready_idle, teach_program, wait_frames

pytestmark = pytest.mark.browser

# Raised and pointing away from the blocks (they lie in y > 0): waist near -180° points the arm along -y.
RAISED_AWAY_RAD = [-2.5, 0.0, 0.0, 0.0, 0.0]


@pytest.fixture()
def page(browser, server):
    ready_idle(server)
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


def log_lines(page) -> list[str]:
    return page.eval_on_selector_all("#event-log li span", "spans => spans.map(s => s.textContent)")


def wait_log_line(page, text: str, timeout_ms: int = 10_000) -> None:
    page.wait_for_function(
        "(t) => [...document.querySelectorAll('#event-log li span')].some(s => s.textContent.includes(t))",
        arg=text,
        timeout=timeout_ms,
    )


def run_a_job(server) -> None:
    """A calibration: a job, so that the status carries a last job from now on."""
    before = (server.get("/api/status").get("job") or {}).get("id")
    server.post("/api/calibrate")
    server.wait_status(
        lambda s: (s.get("job") or {}).get("id") not in (None, before) and s["job"]["state"] != "running" and s["state"] == "idle",
        60.0,
        "the calibration job to end",
    )


def test_manual_commands_get_a_log_line_after_a_job(page, server):
    run_a_job(server)
    page.evaluate("window.armlab.log.clear()")
    for button, line in [("#btn-home", "home: ok"), ("[data-jog='z-']", "jog z"), ("#btn-sleep", "sleep: ok"),
                         ("#btn-close", "gripper close: ok"), ("#btn-open", "gripper open: ok")]:
        page.wait_for_function("(sel) => !document.querySelector(sel).disabled", arg=button, timeout=10_000)
        page.click(button)
        wait_log_line(page, line)
        server.wait_status(lambda s: not s["moving"] and s["state"] == "idle", 20.0, f"{button} done")
    page.click("#btn-estop")
    page.wait_for_function("!document.getElementById('btn-reset').disabled", timeout=5_000)
    page.click("#btn-reset")
    wait_log_line(page, "reset: ok")
    server.wait_status(lambda s: s["state"] == "idle", 5.0, "reset")
    assert page.errors == []


def test_a_cancel_is_logged_once(page, server):
    program = teach_program(server, "cancel-once", [[0.4, -0.2, 0.3, 0.6, 0.0], [-0.4, -0.1, 0.2, 0.7, 0.3]])
    server.post(f"/api/programs/{program['id']}/repeat", {"cycles": 20})
    page.wait_for_function("!document.getElementById('btn-cancel-job').disabled", timeout=10_000)
    page.evaluate("window.armlab.log.clear()")
    page.click("#btn-cancel-job")
    server.wait_status(lambda s: s["state"] == "idle", 10.0, "the cancelled repeat to end")
    wait_log_line(page, "cancelled")
    wait_log_line(page, "→ idle")
    # Everything the station sent up to now has arrived: a telemetry message newer than the end is drawn.
    end_s = server.get("/api/status")["time_s"]
    page.wait_for_function("(t) => window.armlab.status.time_s > t", arg=end_s, timeout=5_000)
    cancel_lines = [line for line in log_lines(page) if "cancel" in line.lower()]
    assert len(cancel_lines) == 1, cancel_lines
    assert page.errors == []


def test_joint_plot_range_comes_from_the_joint_limits_and_its_legend_shows(page, server):
    server.wait_status(lambda s: not s["moving"], 20.0, "the arm still")
    page.wait_for_function("window.armlab.plot.sampleCount > 10", timeout=10_000)
    labels = page.eval_on_selector_all("#joint-plot .u-legend .u-series .u-label", "ls => ls.map(l => l.textContent)")
    names = server.get("/api/status")["joint_names"]
    assert all(name in labels for name in names), labels
    for i in range(len(labels)):
        why = in_view_and_on_top(page, f"#joint-plot .u-legend .u-series:nth-child({i + 1}) .u-label")
        assert not why, why

    limits_rad = server.get("/api/status")["joint_limits_rad"]  # the server's arm config
    low_deg = math.degrees(min(lo for lo, _ in limits_rad))
    high_deg = math.degrees(max(hi for _, hi in limits_rad))
    y_min, y_max = page.evaluate("window.armlab.plot.yRange")
    assert y_min == pytest.approx(low_deg, abs=0.01) and y_max == pytest.approx(high_deg, abs=0.01)
    assert page.errors == []
