"""Helpers shared by the browser tests (page opening, frame waits, camera pixel → page point)."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# The control lease's name the test pages and the tests' REST helper (conftest.Server) share: one operator
# driving the station from the page and from a script at once.
OPERATOR = "operator"


def open_page(browser, url: str):
    """A new page at `url` with page errors collected in page.errors (a test asserts it stays empty).
    A page opened with the control token is the OPERATOR controller, like the REST helper."""
    if "token=" in url and "controller=" not in url:
        url += f"&controller={OPERATOR}"
    page = browser.new_page(viewport={"width": 1600, "height": 1000})
    page.errors = []
    page.on("pageerror", lambda error: page.errors.append(str(error)))
    page.goto(url)
    return page


def wait_frames(page, at_least: int, timeout_s: float = 30.0) -> int:
    """Wait until the canvas has drawn at least `at_least` frames; returns the count."""
    page.wait_for_function(
        f"Number(document.getElementById('live').dataset.frames || 0) >= {at_least}", timeout=timeout_s * 1000
    )
    return int(page.eval_on_selector("#live", "c => Number(c.dataset.frames)"))


def canvas_point(page, u_px: float, v_px: float) -> tuple[float, float]:
    """Page coordinates of camera pixel (u, v) in the live canvas (object-fit: contain, frame scaling)."""
    return tuple(
        page.evaluate(
            """([u, v]) => {
                const live = window.armlab.live;
                const cam = live.cameraSize();
                const canvas = document.getElementById('live');
                const r = canvas.getBoundingClientRect();
                const fu = u * canvas.width / cam.w, fv = v * canvas.height / cam.h;
                const s = Math.min(r.width / canvas.width, r.height / canvas.height);
                const ox = (r.width - canvas.width * s) / 2, oy = (r.height - canvas.height * s) / 2;
                return [r.left + ox + fu * s, r.top + oy + fv * s];
            }""",
            [u_px, v_px],
        )
    )
