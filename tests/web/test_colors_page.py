"""Colour calibration from the page (issue 17 item 2): in the "Name colour" click mode the operator picks
a colour and clicks a block on the video; the station takes the sample (listed in the Colours panel and
over REST); a click on bare board named as a colour is refused with the station's reason and changes
nothing; Reset returns to the defaults. Uses the shared server and leaves it at its defaults."""

from __future__ import annotations

import pytest

from browser_helpers import canvas_point, enter_click_mode, open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser


def test_name_a_blocks_colour_from_the_page(browser, server):
    ready_idle(server)
    if not server.get("/api/calibration")["calibrated"]:
        server.post("/api/calibrate?wait=true")
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        detections = server.get("/api/detections")["data"]
        block = next(d for d in detections if d["is_cube"] and d["color"] == "green")
        u, v = block["center_px"]
        # The mode buttons are enabled once the page has the camera model (a loaded machine: seconds after the first
        # frames); a click on a disabled one did nothing and the block's click then took no sample.
        enter_click_mode(page, "color")
        page.wait_for_function("document.getElementById('live').dataset.mode === 'color'", timeout=10_000)
        page.select_option("#colors-name", "green")
        page.mouse.click(*canvas_point(page, u, v))
        page.wait_for_function("document.querySelectorAll('#colors-samples li').length === 1"
                               " || document.getElementById('colors-message').dataset.refused === 'true'", timeout=30_000)
        message = page.text_content("#colors-message")
        assert page.eval_on_selector_all("#colors-samples li", "lis => lis.length") == 1, message
        assert message.startswith("green at") and "read green before" in message, message
        samples = server.get("/api/colors")["samples"]
        assert [s["name"] for s in samples] == ["green"] and abs(samples[0]["u"] - u) < 3

        page.select_option("#colors-name", "red")
        page.mouse.click(*canvas_point(page, u + 160, v + 10))  # bare board, away from the cubes
        page.wait_for_function("document.getElementById('colors-message').dataset.refused === 'true'", timeout=30_000)
        refused = page.text_content("#colors-message")
        assert "reads grey" in refused and "unchanged" in refused, refused
        assert len(server.get("/api/colors")["samples"]) == 1

        swatches = page.evaluate("""async () => {
            const { labToCss } = await import('/js/colors.js');
            return [labToCss([50, 0, 0]), labToCss([39.4, 52.5, 21.7]), labToCss(null)];
        }""")
        grey, red, none = swatches
        assert len(set(grey[4:-1].split(","))) == 1 and none == ""  # the board's grey is grey; no Lab, no swatch
        r, g, b = (int(x) for x in red[4:-1].split(","))
        assert r > 2 * g and r > 2 * b  # the red reference shows red (unknown faces are drawn as measured)

        page.click("#btn-colors-reset")
        page.wait_for_function("document.querySelectorAll('#colors-samples li').length === 0", timeout=30_000)
        assert server.get("/api/colors")["samples"] == []
        assert page.errors == []
    finally:
        server.request("DELETE", "/api/colors/samples")
        page.close()
