"""The key hint says what the keys do now (issue 21, Misleading 6): with a joint slider focused the arrow keys move
that joint (the browser's range input), not the Cartesian jog; the hint under the jog pad then names the joint,
and says the jog keys again once the focus leaves the slider. Checked against what the keys really do (the
simulated arm's joints through the status; the page's log of the jog step)."""

from __future__ import annotations

import math

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

HINT = "#jog-keys"


def hint(page, keys: str) -> tuple[str, str]:
    """The hint's text and what it says the keys do, read together once it says `keys` (the page updates it just after
    the focus moves: a focusout's next element is known only then), or as it stands after 5 s."""
    try:
        page.wait_for_function(f"document.querySelector('{HINT}').dataset.keys === '{keys}'", timeout=5_000)
    except PlaywrightTimeout:
        pass  # the assertion after says what it showed
    return tuple(page.eval_on_selector(HINT, "el => [el.textContent, el.dataset.keys]"))


def test_the_key_hint_follows_the_focus_and_says_what_the_arrows_move(browser, server):
    ready_idle(server)
    server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_function("document.getElementById('slider-waist') && !document.getElementById('slider-waist').disabled",
                               timeout=10_000)
        page.click("#live")
        text, keys = hint(page, "jog")
        assert keys == "jog" and "x/y" in text, text

        page.focus("#slider-waist")
        text, keys = hint(page, "slider")
        assert keys == "slider" and "waist" in text and "x/y" not in text, text
        before = ready_idle(server)["joints_rad"]
        page.evaluate("window.armlab.log.clear()")
        page.keyboard.press("ArrowRight")  # what the hint says: the waist's slider moves the waist
        after = server.wait_status(lambda s: abs(s["joints_rad"][0] - before[0]) > math.radians(0.3) and not s["moving"],
                                   20.0, "the waist to turn")["joints_rad"]
        assert after[0] - before[0] == pytest.approx(math.radians(0.5), abs=math.radians(0.2)), (before, after)
        assert all(abs(a - b) < math.radians(0.2) for a, b in zip(after[1:], before[1:])), (before, after)
        lines = page.eval_on_selector_all("#event-log li", "els => els.map(e => e.textContent)")
        assert not any("jog" in line for line in lines), lines

        page.click("#live")  # the focus leaves the slider: the arrows jog again, and the hint says so
        text, keys = hint(page, "jog")
        assert keys == "jog" and "x/y" in text and "waist" not in text, text
        page.evaluate("window.armlab.log.clear()")
        page.keyboard.press("ArrowRight")
        page.wait_for_function("[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes('jog x'))",
                               timeout=10_000)
        assert page.errors == []
    finally:
        page.close()
        ready_idle(server)
        server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
