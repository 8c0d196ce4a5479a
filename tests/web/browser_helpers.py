"""Helpers shared by the browser tests (page opening, frame waits, camera pixel → page point)."""

from __future__ import annotations

import time
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


def page_with_the_arm_at(browser, server, q_rad, ready_js: str):
    """The operator's page, opened once the idle arm stands at q_rad and showing frames, when ready_js holds (its
    controls enabled); the caller closes it."""
    ready_idle(server)
    server.post("/api/arm/joints?wait=true", {"q_rad": list(q_rad), "moving_time_s": 1.0})
    ready_idle(server)
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    wait_frames(page, 2)
    page.wait_for_function(ready_js, timeout=15_000)
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


def teach_program(server, name: str, poses_rad) -> dict:
    """Teach a program over REST (the calls the page makes): start, move to each pose and record, save.
    Returns the stored program."""
    server.post("/api/teach/start")
    for q in poses_rad:
        server.post("/api/arm/joints?wait=true", {"q_rad": [float(v) for v in q], "moving_time_s": 0.8})
        server.wait_status(lambda s: not s["moving"], 10.0, "the arm to settle")
        server.post("/api/teach/record")
    return server.post("/api/teach/stop", {"name": name})


def in_view_and_on_top(page, selector: str) -> str:
    """'' when the element is inside the viewport and is what a click at its centre hits; else why not."""
    return page.evaluate(
        """(sel) => {
            const el = document.querySelector(sel);
            if (!el) return `${sel}: missing`;
            const r = el.getBoundingClientRect();
            const w = window.innerWidth, h = window.innerHeight;
            if (r.width === 0 || r.height === 0) return `${sel}: not shown`;
            if (r.left < 0 || r.top < 0 || r.right > w || r.bottom > h)
                return `${sel}: at ${r.left.toFixed(0)},${r.top.toFixed(0)}..${r.right.toFixed(0)},${r.bottom.toFixed(0)} outside ${w}x${h}`;
            const hit = document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2);
            if (!hit || !(hit === el || el.contains(hit))) return `${sel}: covered by ${hit ? hit.outerHTML.slice(0, 80) : 'nothing'}`;
            return '';
        }""",
        selector,
    )


def ready_idle(server, timeout_s: float = 60.0) -> dict:
    """Wait for idle with the arm still, resetting estop, and a fault whose devices are back (a loaded machine
    can starve the simulated camera past its watchdog), and leaving a teach session a failed test left open (its
    draft discarded: one failure in teach mode once failed the 13 page tests after it); fails naming the last status."""
    deadline = time.monotonic() + timeout_s
    status = {}
    while time.monotonic() < deadline:
        status = server.get("/api/status")
        if status["state"] == "idle" and not status["moving"]:
            return status
        if status["state"] in ("estop", "fault") and not status.get("devices_lost"):
            server.request("POST", "/api/reset")
        if status["state"] == "teach" and not status["moving"]:
            server.request("POST", "/api/teach/exit")
        time.sleep(0.1)
    raise AssertionError(f"not idle after {timeout_s} s; last status: {status}")


def enter_click_mode(page, mode: str = "grab", timeout_ms: int = 15_000) -> None:
    """Click the Click-grab/drop mode button once the page has the camera model and the button is enabled."""
    button = f"#click-mode [data-mode='{mode}']"
    page.wait_for_function(f"window.armlab.live.cameraModel !== null && !document.querySelector(\"{button}\").disabled",
                           timeout=timeout_ms)
    page.click(button)
