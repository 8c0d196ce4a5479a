"""Layouts that do not move under the cursor (issue 21, Misleading 3): the pointer entering the video lengthened the
readout, the toolbar re-wrapped and the video moved 39 px down. At several window widths, the video's box (and the
toolbar's) is the same before and while the pointer reads world points over it, over the board and over a block."""

from __future__ import annotations

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from browser_helpers import canvas_point, ready_idle, wait_frames

pytestmark = pytest.mark.browser

WIDTHS = (1600, 1280, 1100, 900)
BOXES = """() => Object.fromEntries(['live', 'view-wrap', 'hover-world'].map(id => {
    const r = document.getElementById(id).getBoundingClientRect();
    return [id, [r.left, r.top, r.width, r.height].map(v => Math.round(v * 10) / 10)];
}))"""


def hover_and_wait(page, u: float, v: float) -> str:
    """Move the pointer over camera pixel (u, v) and wait for the readout's answer there; returns its text."""
    page.evaluate("(() => { const e = document.getElementById('hover-world'); delete e.dataset.pixel;"
                  " e.dataset.hidden = 'false'; e.textContent = 'x waiting'; })()")
    x, y = canvas_point(page, u, v)
    page.mouse.move(x, y)
    # the readout asks the server (pixel-to-world): a loaded machine (the suite in parallel) takes seconds. It
    # answers with a reading (a pixel set) or says why not (its title is the server's message): either ends the wait.
    answered = True
    try:
        page.wait_for_function("(() => { const e = document.getElementById('hover-world');"
                               " return e.dataset.pixel !== undefined || e.dataset.hidden === 'true'"
                               " || !e.textContent.startsWith('x'); })()", timeout=30_000)
    except PlaywrightTimeout:
        answered = False
    readout = page.evaluate("([x, y]) => { const e = document.getElementById('hover-world'); const top ="
                            " document.elementFromPoint(x, y); return [e.dataset.pixel, e.textContent, e.title,"
                            " top ? `${top.tagName}#${top.id}.${top.className}` : null]; }", [x, y])
    assert answered and readout[0] is not None, (
        f"no reading at ({u:.0f}, {v:.0f}) px, page point ({x:.0f}, {y:.0f}) under {readout[3]}: "
        f"{readout[1]!r} ({readout[2]!r}){'' if answered else ', no answer in 30 s'}")
    return readout[1]


def test_the_video_does_not_move_when_the_pointer_reads_it(browser, server):
    # The arm folded out of the camera's way: a spot it hid since it was last seen has no reading (the readout says
    # so and sets no pixel); another module's test may have left it over the blocks.
    ready_idle(server)
    server.post("/api/arm/sleep?wait=true", {"moving_time_s": 2.0})
    status = ready_idle(server)
    if status["calibration_state"] != "trusted":
        server.post("/api/calibrate?wait=true", timeout_s=90.0)
        server.wait_status(lambda s: s["calibration_state"] == "trusted" and s["state"] == "idle", 60.0, "calibrated")
    server.wait_status(lambda s: server.get("/api/detections")["data"], 30.0, "the scene's cubes detected")
    blocks = server.get("/api/detections")["data"]
    page = browser.new_page(viewport={"width": WIDTHS[0], "height": 1000})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(f"{server.base_url}/?token={server.token}&controller=operator")
    try:
        wait_frames(page, 2)
        for width in WIDTHS:
            page.set_viewport_size({"width": width, "height": 1000})
            page.mouse.move(1, 1)  # off the video
            page.wait_for_function("document.getElementById('hover-world').dataset.pixel === undefined "
                                   "|| document.getElementById('hover-world').textContent.startsWith('x —')", timeout=5_000)
            frames = int(page.eval_on_selector("#live", "c => Number(c.dataset.frames)"))
            wait_frames(page, frames + 2)
            before = page.evaluate(BOXES)
            texts = [hover_and_wait(page, *blocks[0]["center_px"]), hover_and_wait(page, 640.0, 600.0)]
            during = page.evaluate(BOXES)
            assert during == before, (width, texts, before, during)
            assert len(texts[0]) > 30, texts  # the long reading (pixel, depth, x, y, z) really was shown
        assert errors == []
    finally:
        page.close()
