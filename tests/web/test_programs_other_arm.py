"""The teach panel on a UR3 station whose database also holds an RX200 program (issue 21, broken item 1).
Before, GET /api/programs answered 422 and the panel said "no programs yet" right after a save, with no error
shown. Now the panel lists the program just saved through its buttons and says how many programs of other arms
the file holds. Real `armlab serve --workcell ur3_suction`, real Chromium."""

from __future__ import annotations

import pytest
from browser_helpers import open_page, wait_frames
from conftest import running_server

from armlab.store import Owner, Store, Waypoint

pytestmark = pytest.mark.browser


def test_the_teach_panel_lists_this_arms_program_and_counts_the_rx200s(browser, tmp_path):
    rx200 = Owner("rx200", "rx200_armlab", 5)
    Store(tmp_path / "armlab.sqlite3").save_program("rx200 wave", [Waypoint((0.0,) * 5, "release")], owner=rx200)
    with running_server(tmp_path, ("--workcell", "ur3_suction", "--seed", "1")) as server:
        server.wait_status(lambda s: s["state"] == "idle" and not s["moving"], 30.0, "idle")
        page = open_page(browser, f"{server.base_url}/?token={server.token}")
        try:
            wait_frames(page, 1)
            page.wait_for_function("!document.getElementById('btn-teach-start').disabled", timeout=15_000)
            page.click("#btn-teach-start")
            page.wait_for_function("!document.getElementById('btn-teach-record').disabled", timeout=5_000)
            page.click("#btn-teach-record")
            page.wait_for_function("document.querySelectorAll('#draft-table tbody tr').length === 1", timeout=5_000)
            page.fill("#teach-name", "ur3 pose")
            page.click("#btn-teach-stop")
            page.wait_for_function(
                "[...document.querySelectorAll('#program-list li span')].some(s => s.textContent === 'ur3 pose')", timeout=10_000)
            names = page.eval_on_selector_all("#program-list li span", "els => els.map(e => e.textContent)")
            assert names == ["ur3 pose"]  # this arm's only
            others = page.text_content("#program-others")
            assert page.is_visible("#program-others") and "1 program of other arms" in others and "rx200" in others, others
            stored = server.get("/api/programs")
            assert [p["name"] for p in stored["data"]] == ["ur3 pose"] and stored["others_count"] == 1
        finally:
            page.close()
