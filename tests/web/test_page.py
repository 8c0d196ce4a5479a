"""The page against the real server: it loads, frames stream in, state and buttons follow the station,
view-only visitors cannot command, refused commands show the server's own sentence."""

from __future__ import annotations

import math
import time

import pytest

from browser_helpers import open_page, wait_frames

pytestmark = pytest.mark.browser


@pytest.fixture()
def page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    yield page
    page.close()


def test_page_loads_streams_frames_and_mirrors_status(page, server):
    first = wait_frames(page, 3)
    later = wait_frames(page, first + 5)
    assert later >= first + 5

    # The token left the address bar but stays for this tab.
    assert "token" not in page.url
    assert page.evaluate("sessionStorage.getItem('armlab.token')") == server.token

    page.wait_for_function("document.getElementById('conn-text').textContent === 'connected'")
    page.wait_for_function("Number(document.getElementById('fps').textContent) > 0", timeout=10_000)
    assert page.text_content("#control-mode") == "control"
    latency_ms = float(page.text_content("#latency"))
    assert 0 <= latency_ms < 5000

    status = server.get("/api/status")
    assert page.text_content("#state-badge") == status["state"]
    # Joint readout shows the station's joints in degrees.
    page.wait_for_function("window.armlab.status && window.armlab.status.joints_rad.length === 5")
    ui_joints_rad = page.evaluate("window.armlab.status.joints_rad")
    rows = page.eval_on_selector_all("#joint-readout tr", "rows => rows.map(r => r.cells[1].textContent)")
    assert len(rows) == 5
    for shown, q in zip(rows, ui_joints_rad):
        assert math.isclose(float(shown.rstrip("°")), math.degrees(q), abs_tol=0.06)

    # Exactly the allowed commands are enabled, but for a button the page blocks itself with its reason: only
    # click calibration's Fit, until 4 points are clicked.
    allowed = set(page.evaluate("window.armlab.status.allowed_commands"))
    buttons = page.eval_on_selector_all(
        "button[data-command]", "bs => bs.map(b => [b.id, b.dataset.command, b.disabled, b.dataset.blocked || ''])"
    )
    assert buttons, "no command buttons on the page"
    blocked = {button_id: reason for button_id, _, _, reason in buttons if reason}
    assert blocked == {"btn-clickcal-fit": "click at least 4 points"}, blocked
    for button_id, command, disabled, reason in buttons:
        expected = bool(reason) or command not in allowed
        assert disabled == expected, f"button '{button_id}' for '{command}' disabled={disabled}, allowed={allowed}"
    assert not page.is_disabled("#btn-estop")

    # The joint plot has collected samples at telemetry rate.
    page.wait_for_function("window.armlab.plot.sampleCount > 10", timeout=10_000)
    assert page.errors == []


def test_view_only_page_streams_but_cannot_command(browser, server):
    page = open_page(browser, server.base_url + "/")
    try:
        wait_frames(page, 3)
        page.wait_for_function("window.armlab.status !== null")
        assert page.text_content("#control-mode") == "view only"
        disabled = page.eval_on_selector_all("button[data-command]", "bs => bs.map(b => b.disabled)")
        assert disabled and all(disabled)
        assert page.errors == []
    finally:
        page.close()


def test_view_toggle_changes_the_stream(page, server):
    wait_frames(page, 2)
    page.click("#view-select button[data-view='depth']")
    page.wait_for_function("document.getElementById('live').dataset.view === 'depth'", timeout=15_000)
    # Top-down needs a calibration: its button stays disabled until then.
    assert page.is_disabled("#view-select button[data-view='topdown']") == (not server.get("/api/status")["calibrated"])
    page.click("#view-select button[data-view='color']")
    page.wait_for_function("document.getElementById('live').dataset.view === 'color'", timeout=15_000)
    assert page.errors == []


def test_refused_command_shows_the_servers_message(page, server):
    wait_frames(page, 2)
    page.wait_for_function("window.armlab.status && window.armlab.status.gripper_pose")
    # A Cartesian target far out of reach: the station refuses and the toast carries its sentence.
    response = server.request("POST", "/api/arm/pose", json={"position_m": [0.0, 0.9, 0.05]})
    assert response.status_code == 422
    server_message = response.json()["error"]["message"]
    page.evaluate("window.armlab.run('far move', () => window.armlab.api.pose([0.0, 0.9, 0.05]))")
    toast = page.locator(".toast[data-level='error']").last
    toast.wait_for(timeout=5_000)
    assert server_message in toast.text_content()
    assert page.errors == []


def test_page_reconnects_by_itself(page, server):
    wait_frames(page, 2)
    page.wait_for_function("document.getElementById('conn-text').textContent === 'connected'")
    # Drop the websocket as a network failure would (not a user close): the page must come back.
    page.evaluate("window.armlab.stream.ws.close()")
    page.wait_for_function("document.getElementById('conn-text').textContent === 'reconnecting'", timeout=5_000)
    page.wait_for_function("document.getElementById('conn-text').textContent === 'connected'", timeout=10_000)
    frames = wait_frames(page, 1)
    wait_frames(page, frames + 3)  # frames flow again (acks resumed on the new connection)
    log = page.text_content("#event-log")
    assert "connection lost" in log
    assert page.errors == []


def test_estop_button_falls_back_to_rest_without_the_websocket(page, server):
    wait_frames(page, 2)
    page.wait_for_function("window.armlab.status && window.armlab.status.state === 'idle'")
    page.evaluate("window.armlab.stream.close()")  # websocket down for good
    page.wait_for_function("document.getElementById('conn-text').textContent === 'reconnecting'")
    page.click("#btn-estop")
    status = server.wait_status(lambda s: s["state"] == "estop", 3.0, "e-stop over REST")
    assert status["state"] == "estop"
    assert "E-STOP pressed (REST)" in page.text_content("#event-log")
    server.post("/api/reset")
    server.wait_status(lambda s: s["state"] == "idle", 3.0, "reset")
    assert page.errors == []


def test_wrong_token_falls_back_to_view_only_with_a_message(browser, server):
    page = open_page(browser, f"{server.base_url}/?token=not-the-token")
    try:
        toast = page.locator(".toast", has_text="control token rejected")
        toast.wait_for(timeout=10_000)
        wait_frames(page, 3)  # the view-only stream works
        assert page.text_content("#control-mode") == "view only"
        assert page.evaluate("sessionStorage.getItem('armlab.token')") is None
        disabled = page.eval_on_selector_all("button[data-command]", "bs => bs.map(b => b.disabled)")
        assert disabled and all(disabled)
        assert page.errors == []
    finally:
        page.close()


def test_cartesian_jog_moves_the_gripper_by_the_step(page, server):
    wait_frames(page, 2)
    server.post("/api/arm/joints?wait=true", {"q_rad": [0.0, 0.0, 0.3, 0.0, 0.0], "moving_time_s": 1.0})
    start = server.wait_status(lambda s: s["state"] == "idle" and not s["moving"], 10.0, "the arm to settle")
    page.wait_for_function("!document.querySelector(\"[data-jog='z-']\").disabled", timeout=5_000)
    page.wait_for_function(
        "p => Math.abs(window.armlab.status.gripper_pose.position_m[2] - p) < 2e-3",  # the page has a fresh status (the held arm drifts a little)
        arg=start["gripper_pose"]["position_m"][2],
    )
    page.select_option("#jog-step", "0.05")
    page.click("[data-jog='z-']")
    p0 = start["gripper_pose"]["position_m"]
    end = server.wait_status(
        lambda s: not s["moving"] and s["gripper_pose"]["position_m"][2] < p0[2] - 0.04, 10.0, "the jog to end"
    )
    p1 = end["gripper_pose"]["position_m"]
    assert p1[2] == pytest.approx(p0[2] - 0.05, abs=0.003)
    assert p1[0] == pytest.approx(p0[0], abs=0.003) and p1[1] == pytest.approx(p0[1], abs=0.003)
    assert end["gripper_pose"]["pitch_rad"] == pytest.approx(start["gripper_pose"]["pitch_rad"], abs=0.02)
    # The joint sliders follow the arm once it has moved (the operator did not touch them).
    page.wait_for_function(
        "q => Math.abs(Number(document.getElementById('slider-elbow').value) - q) < 0.6",
        arg=math.degrees(end["joints_rad"][2]),
        timeout=5_000,
    )
    assert page.errors == []


def settled_gripper(server, command: str, timeout_s: float = 10.0) -> dict:
    """The gripper state once `command` is active and its width stopped changing (two polls 0.2 s apart)."""
    deadline = time.monotonic() + timeout_s
    previous = None
    while time.monotonic() < deadline:
        gripper = server.get("/api/status")["gripper"]
        if gripper["command"] == command and previous is not None and abs(gripper["width_m"] - previous) < 0.0005:
            return gripper
        previous = gripper["width_m"] if gripper["command"] == command else None
        time.sleep(0.2)
    raise AssertionError(f"gripper did not settle on '{command}' within {timeout_s} s")


def test_gripper_buttons_close_and_open_the_gripper(page, server):
    wait_frames(page, 2)
    page.wait_for_function("!document.getElementById('btn-close').disabled", timeout=5_000)
    opened = settled_gripper(server, "release")
    page.click("#btn-close")
    closed = settled_gripper(server, "grasp")
    assert closed["width_m"] < opened["width_m"] - 0.02
    # The readout shows the closed width (mm) the station reports.
    page.wait_for_function(
        """w => {
            const m = document.getElementById('pose-readout').textContent.match(/width ([0-9.]+) mm/);
            return m !== null && Math.abs(Number(m[1]) - w) < 1;
        }""",
        arg=closed["width_m"] * 1000,
        timeout=5_000,
    )
    page.click("#btn-open")
    reopened = settled_gripper(server, "release")
    assert reopened["width_m"] == pytest.approx(opened["width_m"], abs=0.003)
    assert page.errors == []
