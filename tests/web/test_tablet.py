"""The page on a tablet (issue 21, "Tablet"): 768 x 1024 with touch (Playwright has_touch/is_mobile, real touch
input through the DevTools protocol). A finger holding a joint's + button jogs the arm and lifting it stops the arm
(ground truth, the deadman's bound as in test_hold_jog); a second finger tapping E-STOP while the first still holds
halts it; the video stays in the viewport, uncovered, throughout; the jog and stop controls are at least 44 x 44 px;
no keyboard hint ('Esc', 'keys: ...') is shown on a touch screen."""

from __future__ import annotations

import pytest

from browser_helpers import OPERATOR, in_view_and_on_top, ready_idle, wait_frames
from hold_helpers import (
    assert_stopped,
    held_until_cruising,
    hold_button_ready,
    station_limits,
    stopped_after,
    to_start,
    truth,
    wait_truth,
)

pytestmark = pytest.mark.browser

TABLET = {"viewport": {"width": 768, "height": 1024}, "has_touch": True, "is_mobile": True, "device_scale_factor": 2}
MIN_TARGET_PX = 44
HOLD = "[data-hold='0+']"


@pytest.fixture
def tablet(browser, server):
    context = browser.new_context(**TABLET)
    page = context.new_page()
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    page.goto(f"{server.base_url}/?token={server.token}&controller={OPERATOR}")
    wait_frames(page, 2)
    hold_button_ready(page)
    page.touch = context.new_cdp_session(page)
    yield page
    context.close()
    ready_idle(server)


def _centre(page, selector: str) -> dict:
    box = page.locator(selector).bounding_box()
    return {"x": box["x"] + box["width"] / 2, "y": box["y"] + box["height"] / 2}


def _touch(page, kind: str, points: list[dict]) -> None:
    """One touch event: the fingers down after it (touchStart/touchEnd press or lift the ones that changed)."""
    page.touch.send("Input.dispatchTouchEvent", {"type": kind, "touchPoints": points})


def _hold_in_view(page) -> dict:
    """Scroll the jog panel up to the bottom of the screen (under the video) and return the + button's touch point."""
    page.eval_on_selector(HOLD, "b => b.scrollIntoView({block: 'end'})")
    page.wait_for_function(f"(() => {{ const r = document.querySelector(\"{HOLD}\").getBoundingClientRect(); "
                           "return r.bottom <= innerHeight && r.top >= 0; })()")
    assert in_view_and_on_top(page, HOLD) == ""
    return {**_centre(page, HOLD), "id": 1}


def _video_in_view(page) -> None:
    assert in_view_and_on_top(page, "#live") == "", "the video is not in view while jogging"


def test_the_tablet_page_has_touch_sized_controls_and_no_keyboard_hints(tablet):
    assert tablet.evaluate("matchMedia('(pointer: coarse)').matches")
    text = tablet.evaluate("document.body.innerText")
    assert "Esc" not in text and "keys:" not in text and "hold keys" not in text, "a keyboard hint is shown on a touch screen"
    sizes = tablet.eval_on_selector_all("#btn-estop, [data-hold], [data-jog]",
                                        "els => els.map(e => [e.dataset.hold || e.dataset.jog || e.id, e.getBoundingClientRect().width, "
                                        "e.getBoundingClientRect().height])")
    assert len(sizes) >= 1 + 10 + 10
    small = [s for s in sizes if s[1] < MIN_TARGET_PX or s[2] < MIN_TARGET_PX]
    assert small == [], f"touch targets under {MIN_TARGET_PX} px: {small}"
    assert tablet.errors == []


def test_a_finger_holds_a_jog_the_video_stays_in_view_and_lifting_it_stops_the_arm(tablet, server):
    start = to_start(server)
    limits = station_limits(tablet)
    tablet.select_option("#hold-speed", "100")
    finger = _hold_in_view(tablet)
    _video_in_view(tablet)
    _touch(tablet, "touchStart", [finger])
    before, _ = held_until_cruising(server, start, limits.top_rad_s, "a finger holds +", tablet)
    _video_in_view(tablet)
    assert in_view_and_on_top(tablet, HOLD) == "", "the held button moved away under the finger"
    _touch(tablet, "touchEnd", [])
    after_event = truth(server)
    stopped, later = stopped_after(server, before)
    assert_stopped("finger lifted", limits, limits.top_rad_s, before, after_event, stopped, later)
    _video_in_view(tablet)
    assert tablet.errors == []


def test_a_tap_on_estop_halts_a_jog_held_by_another_finger(tablet, server):
    start = to_start(server)
    limits = station_limits(tablet)
    tablet.select_option("#hold-speed", "100")
    finger = _hold_in_view(tablet)
    _touch(tablet, "touchStart", [finger])
    before, _ = held_until_cruising(server, start, limits.top_rad_s, "a finger holds +", tablet)
    assert in_view_and_on_top(tablet, "#btn-estop") == ""
    second = {**_centre(tablet, "#btn-estop"), "id": 2}
    _touch(tablet, "touchStart", [finger, second])  # the second finger taps E-STOP, the first still holds +
    _touch(tablet, "touchEnd", [finger])
    after_event = truth(server)
    server.wait_status(lambda s: s["state"] == "estop", 10.0, "the e-stop")
    stopped = wait_truth(server, lambda t: t.time_s >= after_event.time_s + 0.3, 10.0, "0.3 s of sim time after the tap", tablet)
    later = wait_truth(server, lambda t: t.time_s >= stopped.time_s + 0.5, 10.0, "0.5 s more", tablet)
    assert_stopped("e-stop tapped", limits, limits.top_rad_s, before, after_event, stopped, later)
    _touch(tablet, "touchEnd", [])
    _video_in_view(tablet)
    assert tablet.errors == []
