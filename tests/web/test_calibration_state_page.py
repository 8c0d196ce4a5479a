"""One calibration state, shown the same everywhere (issue 21, Misleading 4): after the simulated camera mount is
knocked, the station's status, the Calibration panel and the top bar all say the calibration is not trusted;
detections seen through the knocked camera are drawn and listed marked as such, and click-grab (the mode
button and a click on a detection's row) is refused in the page with the reason, nothing sent, nothing moved."""

from __future__ import annotations

import pytest

from browser_helpers import open_page, wait_frames
from conftest import running_server

pytestmark = pytest.mark.browser

KNOCK = {"translation_m": [0.005, 0.0, 0.0], "rotation_rad": [0.0, 0.0, 0.0175]}  # 5 mm and 1 deg


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    with running_server(tmp_path_factory.mktemp("calibration_state")) as srv:
        yield srv


def page_states(page) -> dict:
    """What each place of the page says about the calibration."""
    return page.evaluate(
        """() => ({
            badge: document.getElementById('calib-badge').textContent,
            badgeOk: document.getElementById('calib-badge').dataset.ok,
            panel: document.getElementById('calib-state').dataset.state,
            panelText: document.getElementById('calib-state').hidden ? '' : document.getElementById('calib-state').textContent,
            top: document.getElementById('ind-calib').dataset.state,
            topText: document.getElementById('ind-calib').textContent,
        })"""
    )


def test_a_knocked_camera_is_untrusted_in_status_panel_and_top_bar_and_its_detections_cannot_be_grabbed(browser, fresh):
    page = open_page(browser, f"{fresh.base_url}/?token={fresh.token}")
    try:
        wait_frames(page, 2)
        page.click("#btn-calibrate")
        fresh.wait_status(lambda s: s["calibration_state"] == "trusted" and s["state"] == "idle", 60.0, "calibrated and trusted")
        page.wait_for_function("document.querySelectorAll('#det-body tr[data-index]').length >= 3", timeout=15_000)
        page.wait_for_function("document.getElementById('ind-calib')?.dataset.state === 'trusted'", timeout=10_000)
        trusted = page_states(page)
        assert trusted["panel"] == "trusted" and trusted["badgeOk"] == "true", trusted
        assert page.is_enabled("#click-mode [data-mode='grab']")
        assert page.evaluate("document.querySelectorAll('#det-body tr.untrusted').length") == 0

        fresh.post("/api/sim/camera/bump", json=KNOCK)
        status = fresh.wait_status(lambda s: s["camera_warning"], 60.0, "the camera-moved warning")
        status = fresh.wait_status(lambda s: s["calibration_state"] == "untrusted", 10.0, "the status to say untrusted")
        page.wait_for_function("!document.getElementById('camera-warning').hidden", timeout=10_000)
        page.wait_for_function("document.getElementById('ind-calib')?.dataset.state === 'untrusted'", timeout=10_000)
        states = page_states(page)
        # the same state in the panel's state line, its badge and the top bar; none of them says trusted/calibrated alone
        assert states["panel"] == "untrusted", states
        assert states["badgeOk"] == "false" and "not trusted" in states["badge"], states
        assert "not trusted" in states["topText"], states
        assert "not trusted" in states["panelText"], states

        # Click-grab and click-drop: disabled, saying why
        for mode in ("grab", "drop"):
            selector = f"#click-mode [data-mode='{mode}']"
            assert page.is_disabled(selector), mode
            assert "not trusted" in (page.get_attribute(selector, "title") or ""), page.get_attribute(selector, "title")

        # detections through the knocked camera: marked in the table and on the live view
        page.wait_for_function("document.querySelectorAll('#det-body tr[data-index]').length > 0", timeout=10_000)
        rows = page.evaluate("[...document.querySelectorAll('#det-body tr[data-index]')].map(r => r.className)")
        assert rows and all("untrusted" in r for r in rows), rows
        assert page.evaluate("document.getElementById('det-count').textContent").endswith("not trusted")
        assert page.evaluate("document.getElementById('live').dataset.detections") == "untrusted"

        # a click on a detection's row in grab mode (forced: the page blocks the mode) sends no grab
        page.evaluate("window.armlab.setMode('grab')")
        jobs_before = status["job"]["id"] if status["job"] else None
        page.evaluate("window.armlab.log.clear()")
        page.click("#det-body tr[data-index='0']")
        page.wait_for_function("[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes('grab refused'))",
                               timeout=5_000)
        lines = page.eval_on_selector_all("#event-log li", "els => els.map(e => e.textContent)")
        assert any("grab refused" in line and "not trusted" in line for line in lines), lines
        after = fresh.get("/api/status")
        assert (after["job"]["id"] if after["job"] else None) == jobs_before and not after["moving"]
        assert page.errors == []
    finally:
        page.close()
