"""Hold-to-run jog in the page (issue 21, "What a pendant user reaches for"): pressing and holding a joint's
button or key moves the arm while held (started, kept going by heartbeats and stopped over the websocket) and it
stops when released, when the page loses focus, and when the page's connection drops. Ground truth from the simulation:
after each event the waist travels no further than the deadman allows from the last truth read before it,
v·(event window + one control period + jog_hold_s) + v²/2a (+ the servo's lag), and stays still afterwards;
all in sim time and joint angles, no wall-clock figures asserted. Key auto-repeat starts no new jogs."""

from __future__ import annotations

import pytest

from browser_helpers import OPERATOR, open_page, wait_frames
from hold_helpers import (
    CRUISE_TRAVEL_RAD,
    assert_stopped,
    held_until_cruising,
    hold_button_ready,
    mouse_down_on,
    open_counting_page,
    station_limits,
    stopped_after,
    to_start,
    truth,
)

pytestmark = pytest.mark.browser


def _page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    wait_frames(page, 2)
    hold_button_ready(page)
    return page


@pytest.mark.parametrize("percent", [25, 100])
def test_a_held_button_moves_at_the_chosen_speed_and_release_stops_it(browser, server, percent):
    start = to_start(server)
    page = _page(browser, server)
    try:
        limits = station_limits(page)
        page.select_option("#hold-speed", str(percent))
        mouse_down_on(page, "[data-hold='0+']")
        v = limits.top_rad_s * percent / 100
        before, fastest = held_until_cruising(server, start, v, "the + button is held", page)
        assert fastest <= 1.1 * v + 0.02, f"the held jog went at {fastest:.3f} rad/s, faster than the chosen {v:.3f} rad/s"
        page.mouse.up()
        after_event = truth(server)
        stopped, later = stopped_after(server, before)
        assert_stopped(f"release at {percent} %", limits, v, before, after_event, stopped, later)
        assert page.errors == []
    finally:
        page.close()


def test_losing_focus_stops_a_held_key(browser, server):
    """Held key 1 (waist +): auto-repeat keydowns start nothing new (one jog message on the websocket); the window
    losing focus stops the jog."""
    start = to_start(server)
    page = open_counting_page(browser, f"{server.base_url}/?token={server.token}&controller={OPERATOR}")
    wait_frames(page, 2)
    hold_button_ready(page)
    try:
        limits = station_limits(page)
        page.select_option("#hold-speed", "100")
        page.click("#live")  # the page focused, not a field
        page.keyboard.down("Digit1")
        for _ in range(5):  # auto-repeat while held: the same key again, with repeat set
            page.keyboard.down("Digit1")
        before, _ = held_until_cruising(server, start, limits.top_rad_s, "key 1 is held", page)
        resent = page.evaluate("window.armlab.holdJog.resent")  # jogs sent again after a late beat of a busy page
        jogs = [m for m in page.sent if m.get("type") in ("jog", "jog_cartesian")]
        assert 1 <= len(jogs) <= 1 + resent, f"the held key (with its auto-repeat) sent {len(jogs)} jogs ({resent} re-sent)"
        page.evaluate("window.dispatchEvent(new FocusEvent('blur'))")  # the operator switched to another window
        after_event = truth(server)
        stopped, later = stopped_after(server, before)
        assert_stopped("blur", limits, limits.top_rad_s, before, after_event, stopped, later)
        page.keyboard.up("Digit1")
        assert page.errors == []
    finally:
        page.context.close()


@pytest.mark.parametrize("how", ["page closed", "network gone"])
def test_a_dropped_connection_stops_a_held_jog(browser, server, how):
    """The page goes away while the button is held (closed; or its network hangs: the websocket carries nothing
    more and REST calls fail, so only the station's deadman can stop the arm)."""
    start = to_start(server)
    context = browser.new_context(viewport={"width": 1600, "height": 1000})
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    link = {"forward": True}
    if how == "network gone":
        def proxy(ws):
            upstream = ws.connect_to_server()
            ws.on_message(lambda message: upstream.send(message) if link["forward"] else None)
            upstream.on_message(lambda message: ws.send(message) if link["forward"] else None)

        page.route_web_socket("**/ws*", proxy)
    try:
        page.goto(f"{server.base_url}/?token={server.token}&controller=operator")
        wait_frames(page, 2)
        hold_button_ready(page)
        limits = station_limits(page)
        page.select_option("#hold-speed", "100")
        mouse_down_on(page, "[data-hold='0+']")
        before, _ = held_until_cruising(server, start, limits.top_rad_s, "the + button is held", page)
        if how == "page closed":
            page.close(run_before_unload=False)
        else:
            link["forward"] = False  # first: Playwright calls (the route below) run the proxy's handlers
            page.route("**/api/**", lambda route: route.abort())
        after_event = truth(server)
        stopped, later = stopped_after(server, before)
        assert_stopped(how, limits, limits.top_rad_s, before, after_event, stopped, later)
        assert stopped.q_rad[0] - start.q_rad[0] >= CRUISE_TRAVEL_RAD
        if how == "network gone":
            assert page.evaluate("window.armlab.holdJog.active !== null"), "the page noticed: this case is the station's deadman"
    finally:
        context.close()
