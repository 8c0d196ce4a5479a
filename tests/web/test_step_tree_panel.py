"""The teach panel's step tree (issue 21, programs that are programs): tick two waypoints of a saved program,
loop them 3 times and add a wait, in the page; the server stores the tree and the table shows the expanded
sequence repeat runs; a loop of 0 typed in the panel is refused and changes nothing."""

from __future__ import annotations

import json

import pytest

from browser_helpers import open_page, ready_idle

pytestmark = pytest.mark.browser

POSES_RAD = [[0.4, -0.2, 0.3, 0.6, 0.0], [0.0, 0.1, 0.2, 0.8, 0.3], [-0.4, -0.1, 0.2, 0.7, 0.0]]


def tick(page, index: int) -> None:
    """Tick top-level step `index` (1-based) (the element's own click, see press); wait until it shows ticked. No
    scrolling first: the list may be drawn again between a scroll and a click (a late programs event under load)
    and the scrolled element is then detached; dispatch_event finds the element and clicks it in one step."""
    page.locator(f"#program-steps > li:nth-child({index}) > label > input").dispatch_event("click")
    page.wait_for_function(f"document.querySelector('#program-steps > li:nth-child({index}) input').checked", timeout=5_000)


def press(page, button: str) -> None:
    """Click a step-tree button (its element's own click: the panel column's layout can shift under a
    pointer click while the live view updates)."""
    page.locator(button).dispatch_event("click")


def stored(server, program_id: int) -> dict:
    return server.get(f"/api/programs/{program_id}")


def test_build_a_loop_and_a_wait_in_the_teach_panel(browser, server):
    ready_idle(server)
    content = json.dumps({"name": "tree-panel", "waypoints": [{"joints_rad": q, "gripper": "release"} for q in POSES_RAD]})
    program = server.post("/api/programs/import", {"format": "json", "content": content})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        page.click("#btn-programs-refresh")
        page.click(f"#program-list li[data-program-id='{program['id']}'] span")
        page.wait_for_function("document.querySelectorAll('#program-steps > li').length === 3", timeout=10_000)
        tick(page, 2)
        tick(page, 3)
        page.fill("#step-loop-count", "3")
        press(page, "#btn-step-loop")
        page.wait_for_function("document.querySelector('#program-steps > li:nth-child(2)')?.dataset.kind === 'loop'", timeout=10_000)
        assert page.inner_text("#program-steps > li:nth-child(2) > label") == "loop × 3"
        assert page.eval_on_selector_all("#program-steps > li:nth-child(2) > ol > li", "lis => lis.length") == 2  # indented body
        page.wait_for_function("document.querySelectorAll('#program-table tbody tr').length === 7", timeout=10_000)
        saved = stored(server, program["id"])
        assert [s.get("kind", "waypoint") for s in saved["steps"]] == ["waypoint", "loop"]
        assert saved["steps"][1]["count"] == 3 and len(saved["waypoints"]) == 1 + 2 * 3
        tick(page, 2)
        page.fill("#step-wait-s", "0.5")
        press(page, "#btn-step-wait")
        page.wait_for_function("document.querySelector('#program-steps > li:nth-child(3)')?.dataset.kind === 'wait'", timeout=10_000)
        saved = stored(server, program["id"])
        assert saved["steps"][2] == {"kind": "wait", "seconds": 0.5} and saved["waypoints"][-1]["dwell_s"] == 0.5
        # a loop of 0 is refused by the server: the tree stays as stored
        tick(page, 1)
        page.fill("#step-loop-count", "0")
        press(page, "#btn-step-loop")
        page.wait_for_function("document.body.innerText.includes('count')", timeout=10_000)
        assert stored(server, program["id"])["steps"] == saved["steps"]
        assert page.errors == []
    finally:
        page.close()
