"""The teach panel as an operator uses it (issue 9, teach and repeat): record three waypoints with the
buttons and the R key, undo, save; edit values in the waypoint table, rename, duplicate, delete; repeat at a
chosen speed with pause and resume; the cycle's joint plot and its CSV download; the program's bag download."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest

from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

POSES_RAD = [[0.4, -0.2, 0.3, 0.6, 0.0], [0.0, 0.1, 0.2, 0.8, 0.3], [-0.4, -0.1, 0.2, 0.7, 0.0]]


def move_to(server, q) -> None:
    server.post("/api/arm/joints?wait=true", {"q_rad": q, "moving_time_s": 0.8})
    server.wait_status(lambda s: not s["moving"], 10.0, "the arm to settle")


def rows(page, table: str) -> int:
    return page.eval_on_selector_all(f"#{table} tbody tr", "trs => trs.length")


def stored(server, name: str) -> dict:
    found = [p for p in server.get("/api/programs")["data"] if p["name"] == name]
    assert len(found) == 1, found
    return found[0]


def test_teach_edit_repeat_pause_plot_and_csv(browser, server, tmp_path):
    ready_idle(server)
    server.wait_status(lambda s: s["state"] == "idle", 30.0, "idle")
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("!document.getElementById('btn-teach-start').disabled", timeout=10_000)
        page.click("#btn-teach-start")
        page.wait_for_function("!document.getElementById('btn-teach-record').disabled", timeout=15_000)
        gripper_at_m = []
        for i, q in enumerate(POSES_RAD):
            move_to(server, q)
            gripper_at_m.append(server.get("/api/status")["gripper_pose"]["position_m"])
            if i == 1:
                page.click("#live")  # the page has the focus, not a field: R records
                page.keyboard.press("r")
            else:
                page.click("#btn-teach-record")
            page.wait_for_function(f"document.querySelectorAll('#draft-table tbody tr').length === {i + 1}", timeout=15_000)
        page.click("#btn-teach-undo")
        page.wait_for_function("document.querySelectorAll('#draft-table tbody tr').length === 2", timeout=15_000)
        page.click("#btn-teach-record")
        page.wait_for_function("document.querySelectorAll('#draft-table tbody tr').length === 3", timeout=15_000)
        page.fill("#teach-name", "panel-wave")
        page.click("#btn-teach-stop")
        page.wait_for_function("document.getElementById('state-badge').textContent === 'idle'", timeout=15_000)
        page.locator("#program-list li", has_text="panel-wave").locator("button", has_text="Edit").click()
        page.wait_for_function("document.querySelectorAll('#program-table tbody tr').length === 3", timeout=15_000)
        program = stored(server, "panel-wave")
        assert np.allclose([w["joints_rad"] for w in program["waypoints"]], POSES_RAD, atol=0.02)
        # The program's path is drawn on the live view: one point per waypoint, where the gripper was.
        page.wait_for_function("document.getElementById('live').dataset.pathPoints === '3'", timeout=15_000)
        shown = page.evaluate("window.armlab.programPath.path.points_m")
        assert np.allclose(shown, gripper_at_m, atol=0.003)

        # Edit: waypoint 2's dwell to 0.5 s, waypoint 1's waist to 10°.
        page.fill("#program-table tbody tr[data-index='1'] input[data-field='dwell']", "0.5")
        page.press("#program-table tbody tr[data-index='1'] input[data-field='dwell']", "Enter")
        page.wait_for_function(
            "window.armlab.teach.selected && window.armlab.teach.selected.waypoints[1].dwell_s === 0.5", timeout=15_000)
        page.fill("#program-table tbody tr[data-index='0'] input[data-field='q0']", "10")
        page.press("#program-table tbody tr[data-index='0'] input[data-field='q0']", "Enter")
        page.wait_for_function(
            "Math.abs(window.armlab.teach.selected.waypoints[0].joints_rad[0] - Math.PI / 18) < 1e-6", timeout=15_000)
        program = stored(server, "panel-wave")
        assert program["waypoints"][1]["dwell_s"] == 0.5
        assert program["waypoints"][0]["joints_rad"][0] == pytest.approx(math.radians(10), abs=1e-6)
        page.fill("#program-table tbody tr[data-index='2'] input[data-field='q1']", "abc")  # refused, nothing stored
        page.press("#program-table tbody tr[data-index='2'] input[data-field='q1']", "Enter")
        page.locator(".toast", has_text="not a number").first.wait_for(timeout=15_000)
        assert stored(server, "panel-wave")["waypoints"] == program["waypoints"]
        with page.expect_download() as info:  # the program as a ROS 2 bag: one MCAP file
            page.click("#program-export-bag")
        assert info.value.suggested_filename == "panel-wave.mcap"
        info.value.save_as(tmp_path / "panel-wave.mcap")
        assert (tmp_path / "panel-wave.mcap").read_bytes().startswith(b"\x89MCAP0\r\n")

        # Rename, duplicate, delete the copy.
        page.fill("#program-name", "panel-wave-2")
        page.click("#btn-program-rename")
        page.wait_for_function("window.armlab.teach.selected && window.armlab.teach.selected.name === 'panel-wave-2'", timeout=15_000)
        count = server.get("/api/programs")["count"]
        page.click("#btn-program-duplicate")
        page.wait_for_function(f"window.armlab.teach.programs.length === {count + 1}", timeout=15_000)
        page.click("#btn-program-delete")  # the copy is selected
        page.wait_for_function(f"window.armlab.teach.programs.length === {count}", timeout=15_000)
        program = stored(server, "panel-wave-2")

        # Repeat 2 cycles at 50 %; pause (the arm holds), resume; the cycle plot and its CSV.
        page.fill("#repeat-cycles", "2")
        # a drag of the slider ends in a change: it sets the station's one speed override (the top bar's), which the
        # slider then follows
        page.eval_on_selector("#repeat-speed", "el => { el.value = '50'; el.dispatchEvent(new Event('input')); "
                                               "el.dispatchEvent(new Event('change')); }")
        server.wait_status(lambda s: s["speed_percent"] == 50, 10.0, "the speed override at 50 %")
        page.locator("#program-list li", has_text="panel-wave-2").locator("button[data-command='repeat']").click()
        server.wait_status(lambda s: s["state"] == "repeat" and s["moving"], 10.0, "the repeat to move the arm")
        page.wait_for_function("!document.getElementById('btn-repeat-pause').disabled", timeout=15_000)
        page.click("#btn-repeat-pause")
        paused = server.wait_status(
            lambda s: (s["job"].get("extra") or {}).get("repeat", {}).get("paused") and not s["moving"], 10.0, "paused and still")
        assert paused["job"]["extra"]["repeat"]["speed_percent"] == 50
        page.wait_for_function("document.getElementById('repeat-progress').textContent.includes('paused')", timeout=15_000)
        page.click("#btn-repeat-resume")
        server.wait_status(lambda s: s["state"] == "repeat" and s["moving"], 10.0, "resumed")
        final = server.wait_status(lambda s: s["state"] == "idle", 120.0, "the repeat to end")
        assert final["job"]["state"] == "succeeded", final["job"]
        # Moved back before the page has seen the repeat end (its status lags the station's under load): the change
        # is still the station's override, not a refused change to the ended job.
        page.evaluate("() => { window.armlab.repeat.jobId = 'a repeat that has ended'; const el = document.getElementById("
                      "'repeat-speed'); el.value = '100'; el.dispatchEvent(new Event('input')); el.dispatchEvent(new Event('change')); }")
        server.wait_status(lambda s: s["speed_percent"] == 100, 10.0, "the speed override back at 100 % (shared server)")
        page.wait_for_function("Number(document.getElementById('cycle-plot').dataset.samples || 0) > 10", timeout=10_000)

        png = page.get_attribute("#btn-cycle-png", "href")
        assert png and png.startswith("data:image/png;base64,") and len(png) > 2000
        page.wait_for_selector("#btn-cycle-csv:not([hidden])")
        with page.expect_download() as info:
            page.click("#btn-cycle-csv")
        path = tmp_path / "cycle.csv"
        info.value.save_as(path)
        table = list(csv.reader(io.StringIO(path.read_text())))
        assert table[0][0] == "t_s" and any("waist" in c for c in table[0]) and len(table) > 10
        assert page.errors == []
    finally:
        page.close()


def test_record_continuously_at_a_rate(browser, server):
    ready_idle(server)
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("!document.getElementById('btn-teach-start').disabled", timeout=10_000)
        page.click("#btn-teach-start")
        page.wait_for_function("!document.getElementById('btn-teach-continuous').disabled", timeout=15_000)
        if rows(page, "draft-table"):  # a draft left over: start from none
            server.post("/api/teach/stop", {"name": "leftover"})
            page.click("#btn-teach-start")
        page.fill("#teach-rate", "5")
        page.click("#btn-teach-continuous")
        page.wait_for_function("document.getElementById('btn-teach-continuous').dataset.recording === 'true'")
        for q in POSES_RAD[:2]:
            server.post("/api/arm/joints?wait=true", {"q_rad": q, "moving_time_s": 1.5})
        page.click("#btn-teach-continuous")
        page.wait_for_function("document.getElementById('btn-teach-continuous').dataset.recording === 'false'")
        page.wait_for_function("document.querySelectorAll('#draft-table tbody tr').length >= 5", timeout=15_000)
        draft = server.get("/api/teach/draft")
        assert draft["count"] >= 5
        # the page shows every recorded row (its table may be one update behind the draft as the recording stops)
        page.wait_for_function(f"document.querySelectorAll('#draft-table tbody tr').length === {draft['count']}", timeout=15_000)
        assert np.allclose(draft["waypoints"][-1]["joints_rad"], POSES_RAD[1], atol=0.03)
        page.fill("#teach-name", "continuous-wave")
        page.click("#btn-teach-stop")
        page.wait_for_function("document.getElementById('state-badge').textContent === 'idle'", timeout=15_000)
        assert page.errors == []
    finally:
        page.close()
