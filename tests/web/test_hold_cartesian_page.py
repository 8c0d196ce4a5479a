"""Cartesian hold-to-run in the page (issue 21, "What a pendant user reaches for"): holding the gripper's x+ button
(mouse, or a finger on a 768x1024 touch screen) or the Z key moves the gripper point along that world axis while
held, over the websocket (jog_cartesian, heartbeats, jog_stop), and it stops when released or when the page loses
focus. Ground truth from the simulation (the gripper point, sim time): the path stays on the axis' line, and after
the event the gripper travels no further than v·(event window + one control period + jog_hold_s) + v²/2a (+ the
servos' lag). Key auto-repeat sends no new jogs. No wall-clock figures asserted."""

from __future__ import annotations

import pytest

from browser_helpers import OPERATOR, in_view_and_on_top, ready_idle, wait_frames
from hold_helpers import (
    assert_cartesian_stop,
    cartesian_limits,
    gripper_truth,
    held_along,
    hold_button_ready,
    mouse_down_on,
    open_counting_page,
    to_pointing_down,
)

pytestmark = pytest.mark.browser

X_PLUS = "[data-hold='x+']"
TABLET = {"viewport": {"width": 768, "height": 1024}, "has_touch": True, "is_mobile": True, "device_scale_factor": 2}


def _page(browser, server, **context_options):
    page = open_counting_page(browser, f"{server.base_url}/?token={server.token}&controller={OPERATOR}", **context_options)
    wait_frames(page, 2)
    hold_button_ready(page, X_PLUS)
    return page


def _jogs_sent(page) -> list[dict]:
    return [m for m in page.sent if m.get("type") in ("jog", "jog_cartesian")]


@pytest.mark.parametrize("percent", [25, 100])
def test_holding_the_x_plus_button_moves_the_gripper_along_x_and_release_stops_it(browser, server, percent):
    start = to_pointing_down(server)
    page = _page(browser, server)
    try:
        top, *_ = cartesian_limits(page)
        page.select_option("#hold-speed", str(percent))
        mouse_down_on(page, X_PLUS)
        v = top * percent / 100
        before, samples = held_along(server, start, 0, v, page, travel_m=0.03 if percent == 100 else 0.01)
        page.mouse.up()
        after_event = gripper_truth(server)
        assert_cartesian_stop(f"x+ released at {percent} %", page, server, 0, v, start, samples, before, after_event)
        sent = _jogs_sent(page)
        assert [m["type"] for m in sent][:1] == ["jog_cartesian"] and sent[0]["axis"] == "x" and sent[0]["velocity_m_s"] > 0
        assert any(m.get("type") == "jog_stop" for m in page.sent), "the release sent no jog_stop"
        assert page.errors == []
    finally:
        page.context.close()
        ready_idle(server)


def test_a_held_z_key_moves_the_gripper_up_auto_repeat_sends_nothing_and_blur_stops_it(browser, server):
    start = to_pointing_down(server)
    page = _page(browser, server)
    try:
        top, *_ = cartesian_limits(page)
        page.select_option("#hold-speed", "100")
        page.click("#live")  # the page focused, not a field
        page.keyboard.down("KeyZ")
        for _ in range(5):  # auto-repeat while held: the same key again, with repeat set
            page.keyboard.down("KeyZ")
        before, samples = held_along(server, start, 2, top, page)
        resent = page.evaluate("window.armlab.holdJog.resent")
        sent = _jogs_sent(page)
        assert 1 <= len(sent) <= 1 + resent, f"the held key (with its auto-repeat) sent {len(sent)} jogs ({resent} re-sent)"
        assert sent[0] == {**sent[0], "type": "jog_cartesian", "axis": "z"}
        page.evaluate("window.dispatchEvent(new FocusEvent('blur'))")  # the operator switched to another window
        after_event = gripper_truth(server)
        assert_cartesian_stop("z+ key, blur", page, server, 2, top, start, samples, before, after_event)
        page.keyboard.up("KeyZ")
        assert page.errors == []
    finally:
        page.context.close()
        ready_idle(server)


def test_on_a_tablet_a_finger_on_x_plus_moves_the_gripper_with_the_video_in_view_and_lifting_it_stops(browser, server):
    start = to_pointing_down(server)
    page = _page(browser, server, **TABLET)
    try:
        top, *_ = cartesian_limits(page)
        page.select_option("#hold-speed", "100")
        page.eval_on_selector(X_PLUS, "b => b.scrollIntoView({block: 'end'})")
        assert in_view_and_on_top(page, X_PLUS) == "" and in_view_and_on_top(page, "#live") == ""
        box = page.locator(X_PLUS).bounding_box()
        assert box["width"] >= 44 and box["height"] >= 44, f"the x+ touch target is {box}"
        finger = {"x": box["x"] + box["width"] / 2, "y": box["y"] + box["height"] / 2, "id": 1}
        touch = page.context.new_cdp_session(page)
        touch.send("Input.dispatchTouchEvent", {"type": "touchStart", "touchPoints": [finger]})
        before, samples = held_along(server, start, 0, top, page)
        assert in_view_and_on_top(page, "#live") == "", "the video left the view while jogging"
        touch.send("Input.dispatchTouchEvent", {"type": "touchEnd", "touchPoints": []})
        after_event = gripper_truth(server)
        assert_cartesian_stop("tablet, finger lifted", page, server, 0, top, start, samples, before, after_event)
        assert page.errors == []
    finally:
        page.context.close()
        ready_idle(server)
