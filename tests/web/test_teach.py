"""Teach mode from the page: start, record two waypoints, stop with a name, see the program listed,
repeat it and watch the arm replay the taught joints; cancel a long repeat from the job line."""

from __future__ import annotations

import numpy as np
import pytest

from browser_helpers import open_page, wait_frames

pytestmark = pytest.mark.browser


def test_teach_record_save_and_repeat_from_the_page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        server.wait_status(lambda s: s["state"] == "idle", 30.0, "idle")
        page.wait_for_function("!document.getElementById('btn-teach-start').disabled", timeout=10_000)
        assert page.is_disabled("#btn-teach-record")  # not teaching yet
        page.click("#btn-teach-start")
        page.wait_for_function("document.getElementById('state-badge').textContent === 'teach'", timeout=5_000)
        page.wait_for_function("!document.getElementById('btn-teach-record').disabled", timeout=5_000)

        poses_rad = [np.array([0.3, -0.2, 0.3, 0.6, 0.0]), np.array([-0.3, -0.1, 0.2, 0.7, 0.2])]
        for q in poses_rad:
            server.post("/api/arm/joints?wait=true", {"q_rad": q.tolist(), "moving_time_s": 0.8})
            server.wait_status(lambda s: not s["moving"], 10.0, "the arm to settle")
            page.click("#btn-teach-record")
            page.wait_for_function(
                "[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes('record waypoint: ok'))"
            )
            page.evaluate("window.armlab.log.clear()")

        page.fill("#teach-name", "ui-test-wave")
        page.click("#btn-teach-stop")
        page.wait_for_function("document.getElementById('state-badge').textContent === 'idle'", timeout=5_000)
        item = page.locator("#program-list li", has_text="ui-test-wave")
        item.wait_for(timeout=5_000)
        assert "2 wp" in item.text_content()
        stored = [p for p in server.get("/api/programs")["data"] if p["name"] == "ui-test-wave"]
        assert len(stored) == 1 and len(stored[0]["waypoints"]) == 2
        for waypoint, q in zip(stored[0]["waypoints"], poses_rad):
            assert np.allclose(waypoint["joints_rad"], q, atol=0.02)

        # Move away, then repeat from the page: the arm goes through the taught poses and returns home.
        server.post("/api/arm/joints?wait=true", {"q_rad": [0.0, 0.0, 0.0, 0.0, 0.0], "moving_time_s": 0.8})
        server.wait_status(lambda s: not s["moving"], 10.0, "the arm to settle")
        page.fill("#repeat-cycles", "1")
        previous_id = (server.get("/api/status").get("job") or {}).get("id")
        item.locator("button[data-command='repeat']").click()
        status = server.wait_status(
            lambda s: s["state"] == "idle" and (s.get("job") or {}).get("name") == "repeat"
            and s["job"]["id"] != previous_id and s["job"]["state"] != "running",
            60.0,
            "the repeat job to finish",
        )
        assert status["job"]["state"] == "succeeded", status["job"]
        assert np.allclose(status["joints_rad"], 0.0, atol=0.03)  # home (DESIGN §4: all zeros) at the end

        # A long repeat shows in the job line with its progress, and the line's Cancel ends it.
        previous_id = status["job"]["id"]
        page.fill("#repeat-cycles", "20")
        item.locator("button[data-command='repeat']").click()
        page.wait_for_selector("#job-line:not([hidden])", timeout=5_000)
        assert "repeat" in page.text_content("#job-name")
        page.wait_for_function("!document.getElementById('btn-cancel-job').disabled", timeout=5_000)
        page.click("#btn-cancel-job")
        status = server.wait_status(
            lambda s: (s.get("job") or {}).get("id") not in (None, previous_id) and s["job"]["state"] != "running",
            10.0,
            "the cancelled repeat to end",
        )
        assert status["job"]["state"] == "cancelled" and status["state"] == "idle", status
        page.wait_for_selector("#job-line", state="hidden", timeout=5_000)
        assert page.errors == []
    finally:
        page.close()
