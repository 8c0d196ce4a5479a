"""E-stop from any page the station serves (issue 9 item 3): a page opened without the token stops the arm
(over the websocket and over REST), and E-STOP, the state and the job's Cancel stay on screen and clickable
during a repeat at 1024 x 768 and 768 x 1024 however the page is scrolled."""

from __future__ import annotations

import pytest

from browser_helpers import in_view_and_on_top, open_page, ready_idle, teach_program, wait_frames

pytestmark = pytest.mark.browser

FAR_POSE_RAD = [0.9, 0.2, 0.1, 0.5, 0.0]
FIXED_ON_SCREEN = ("#btn-estop", "#state-badge", "#btn-cancel-job")


def wait_idle(server) -> None:
    ready_idle(server)


def start_slow_move(server) -> None:
    """A long joint move from home, so the e-stop lands while the arm is moving."""
    server.post("/api/arm/home?wait=true", {"moving_time_s": 1.0})
    server.post("/api/arm/joints", {"q_rad": FAR_POSE_RAD, "moving_time_s": 8.0})
    server.wait_status(lambda s: s["moving"], 5.0, "the arm moving")


def test_a_page_without_the_token_stops_the_arm(browser, server):
    wait_idle(server)
    page = open_page(browser, server.base_url + "/")
    try:
        wait_frames(page, 2)
        page.wait_for_function("window.armlab.status && window.armlab.connected")
        assert page.text_content("#control-mode") == "view only"
        assert not page.is_disabled("#btn-estop")

        start_slow_move(server)
        page.click("#btn-estop")  # over the websocket
        status = server.wait_status(lambda s: s["state"] == "estop", 3.0, "e-stop from the view-only page (websocket)")
        assert abs(status["joints_rad"][0] - FAR_POSE_RAD[0]) > 0.2, "the move ended before the stop: no proof it stopped"
        page.wait_for_function("document.getElementById('state-badge').textContent === 'estop'", timeout=5_000)
        assert "failed" not in page.text_content("#event-log")
        wait_idle(server)

        page.evaluate("window.armlab.stream.close()")  # websocket down for good: the REST fallback
        page.wait_for_function("document.getElementById('conn-text').textContent === 'reconnecting'")
        start_slow_move(server)
        page.click("#btn-estop")
        server.wait_status(lambda s: s["state"] == "estop", 3.0, "e-stop from the view-only page (REST)")
        assert "e-stop failed" not in page.text_content("#event-log")
        assert page.errors == []
    finally:
        page.close()
        wait_idle(server)


@pytest.fixture(scope="module")
def long_program(server) -> dict:
    wait_idle(server)
    return teach_program(server, "estop-screen-wave", [[0.4, -0.2, 0.3, 0.6, 0.0], [-0.4, -0.1, 0.2, 0.7, 0.3]])


@pytest.mark.parametrize("width, height", [(1024, 768), (768, 1024)])
def test_estop_state_and_cancel_stay_on_screen_during_a_repeat(browser, server, long_program, width, height):
    wait_idle(server)
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        page.set_viewport_size({"width": width, "height": height})
        wait_frames(page, 2)
        server.post(f"/api/programs/{long_program['id']}/repeat", {"cycles": 20})
        page.wait_for_function(
            "!document.getElementById('job-line').hidden && document.getElementById('state-badge').textContent === 'repeat'",
            timeout=10_000,
        )

        # Scroll everything that scrolls as far as it goes: the document, every scrolling panel, the last panel into view.
        page.mouse.move(width / 2, height - 40)
        page.mouse.wheel(0, 5000)
        page.evaluate(
            """() => {
                window.scrollTo(0, document.documentElement.scrollHeight);
                document.querySelectorAll('*').forEach((el) => { if (el.scrollHeight > el.clientHeight) el.scrollTop = el.scrollHeight; });
                const panels = document.querySelectorAll('.side-col .panel:not([hidden])');
                panels[panels.length - 1].scrollIntoView();
                document.getElementById('event-log').scrollIntoView();
            }"""
        )
        problems = [why for why in (in_view_and_on_top(page, sel) for sel in FIXED_ON_SCREEN) if why]
        assert not problems, f"at {width}x{height}: {problems}"

        page.click("#btn-estop")
        # The state is e-stop at once; the repeat's thread then unwinds and reports itself cancelled (a status read
        # in between shows it still running: CI, 2026-12-04).
        status = server.wait_status(lambda s: s["state"] == "estop" and s["job"]["state"] != "running", 3.0,
                                    "e-stop clicked during the repeat, and the repeat ended")
        assert status["job"]["state"] == "cancelled", status["job"]
        assert page.errors == []
    finally:
        page.close()
        wait_idle(server)
