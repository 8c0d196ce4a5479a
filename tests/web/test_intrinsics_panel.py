"""The Intrinsics panel (issue 11 item 4) in real Chromium: start a capture, hold the simulated
checkerboard in view (sim route), capture from the page: the view is listed and the coverage canvas
paints the regions it covers; with the board gone, capturing shows 'checkerboard not found' and keeps
nothing; cancel leaves the intrinsics in use as they were."""

from __future__ import annotations

import pytest

from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser


def covered_pixels(page) -> int:
    """Green pixels painted on the coverage canvas (covered cells)."""
    return page.eval_on_selector("#intr-coverage", """c => {
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i + 1] > d[i] + 40 && d[i + 1] > d[i + 2] + 40) n++;
        return n;
    }""")


def test_capture_shows_coverage_and_a_refusal(browser, server):
    ready_idle(server)
    before = server.get("/api/intrinsics")
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 2)
        page.wait_for_selector("#btn-intr-start:not([disabled])", timeout=20_000)
        page.click("#btn-intr-start")
        page.wait_for_function("!document.getElementById('intr-session').hidden", timeout=10_000)
        assert page.text_content("#intr-progress").startswith("0/10 views")
        assert covered_pixels(page) == 0

        # Board in the left half of the image, square to the camera: one view kept, its cells painted.
        server.post("/api/sim/checkerboard", json={"position_m": [-0.12, 0.0, 0.6], "rotation_rad": [0.2, 0.1, 0.0]})
        page.click("#btn-intr-capture")
        page.wait_for_function("document.getElementById('intr-progress').textContent.startsWith('1/10')", timeout=15_000)
        assert page.locator("#intr-views li").count() == 1
        painted = covered_pixels(page)
        width = page.eval_on_selector("#intr-coverage", "c => c.width")
        left = page.eval_on_selector("#intr-coverage", """c => {
            const d = c.getContext('2d').getImageData(0, 0, c.width / 2, c.height).data;
            let n = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i + 1] > d[i] + 40 && d[i + 1] > d[i + 2] + 40) n++;
            return n;
        }""")
        assert painted > 0.1 * width * width * 9 / 16 * 0.25 and left > 0.6 * painted  # the board's side of the image

        # No board in view: the refusal is shown in the panel, nothing is kept.
        server.request("DELETE", "/api/sim/checkerboard")
        page.click("#btn-intr-capture")
        page.wait_for_function("document.getElementById('intr-message').dataset.refused === 'true'", timeout=15_000)
        assert "checkerboard not found" in page.text_content("#intr-message")
        assert page.text_content("#intr-progress").startswith("1/10") and page.locator("#intr-views li").count() == 1
        assert page.is_disabled("#btn-intr-solve")  # 1 of 10 views: nothing to solve yet

        page.click("#btn-intr-cancel")
        page.wait_for_function("document.getElementById('intr-session').hidden", timeout=10_000)
        assert server.get("/api/intrinsics")["intrinsics"] == before["intrinsics"]
        assert page.errors == []
    finally:
        server.request("DELETE", "/api/sim/checkerboard")
        server.request("DELETE", "/api/intrinsics/session")
        page.close()
