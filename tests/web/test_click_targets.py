"""Clicks where users click (issue 9 item 1 from the page): on the arm hanging over the board, on the top block
of a stack, and a grab on a small screen; ground truth from the simulation."""

from __future__ import annotations

import math

import pytest

from browser_helpers import canvas_point, open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser

LARGE_M = 0.038
STACK_XY_M = (0.12, 0.22)
SCENE = [  # a two-block stack and a single block, all in reach
    {"id": "bottom", "type": "block", "color": "blue", "size": "large", "position_m": [*STACK_XY_M, LARGE_M / 2], "yaw_rad": 0.0},
    {"id": "top", "type": "block", "color": "red", "size": "large", "position_m": [*STACK_XY_M, 1.5 * LARGE_M], "yaw_rad": 0.0},
    {"id": "single", "type": "block", "color": "green", "size": "large", "position_m": [-0.12, 0.24, LARGE_M / 2], "yaw_rad": 0.3},
]


def truth(server) -> dict:
    return {o["id"]: o for o in server.get("/api/sim/truth")["objects"]}


def job_after(server, previous_id, timeout_s: float = 60.0) -> dict:
    status = server.wait_status(
        lambda s: (s.get("job") or {}).get("id") not in (None, previous_id) and s["job"]["state"] != "running"
        and s["state"] in ("idle", "fault", "estop"), timeout_s, "the job to end")
    return status["job"]


def pixel_of(server, xy_m) -> tuple[float, float]:
    """The camera pixel the station maps to board point xy_m (Newton steps on POST /api/pixel-to-world)."""
    import numpy as np

    def world(uv):
        return np.array(server.post("/api/pixel-to-world", {"u": float(uv[0]), "v": float(uv[1])})["position_m"][:2])

    uv = np.array([640.0, 360.0])
    for _ in range(6):
        w = world(uv)
        jac = np.column_stack([(world(uv + [6.0, 0.0]) - w) / 6.0, (world(uv + [0.0, 6.0]) - w) / 6.0])
        uv = uv + np.linalg.solve(jac, np.asarray(xy_m) - w)
    return float(uv[0]), float(uv[1])


@pytest.fixture(scope="module")
def stacked_scene(server):
    ready_idle(server)
    if not server.get("/api/status")["calibrated"]:
        server.post("/api/calibrate?wait=true", timeout_s=120)
    server.post("/api/sim/scene", {"objects": SCENE})
    yield
    ready_idle(server)
    server.post("/api/gripper", {"action": "release"})  # a grab that closed on nothing leaves it closed
    server.post("/api/sim/scene", {"event": "pick_sort", "level": 1, "seed": 3})  # the session's scene (conftest)


@pytest.mark.parametrize("width, height", [(1600, 1000), (768, 1024)])
def test_grab_the_top_block_of_a_stack_then_click_on_the_arm(browser, server, stacked_scene, width, height):
    ready_idle(server)
    server.post("/api/sim/scene", {"objects": SCENE})
    server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        page.set_viewport_size({"width": width, "height": height})
        wait_frames(page, 2)
        page.wait_for_function("window.armlab.detections.filter(d => d.is_cube).length >= 2", timeout=30_000)
        top = page.evaluate("window.armlab.detections.reduce((a, d) => (d.position_m[2] > a.position_m[2] ? d : a))")
        assert math.dist(top["position_m"][:2], STACK_XY_M) < 0.015 and top["position_m"][2] > 1.5 * LARGE_M

        page.click("#click-mode button[data-mode='grab']")
        page.locator("#live").scroll_into_view_if_needed()
        previous = (server.get("/api/status").get("job") or {}).get("id")
        page.mouse.click(*canvas_point(page, *top["center_px"]))
        job = job_after(server, previous)
        assert job["state"] == "succeeded", job
        objects = truth(server)
        assert objects["top"]["position_m"][2] > 2 * LARGE_M + 0.02, objects["top"]  # lifted off the stack
        assert objects["bottom"]["position_m"][2] == pytest.approx(LARGE_M / 2, abs=0.004)  # left in place
        page.wait_for_function("window.armlab.live.mode === 'drop'", timeout=5_000)

        # Put it back by REST, then hold the arm over a free board spot and click on the arm in grab mode:
        # the target is the board under the arm, not the arm's own depth; nothing is there, so the grab is
        # refused or fails saying why, nothing is held, and the page stays in grab mode with the message shown.
        server.post("/api/drop?wait=true", {"position_m": [0.0, 0.30, 0.0]})
        spot_m = (0.20, 0.12)
        u, v = pixel_of(server, spot_m)
        server.post("/api/arm/pose?wait=true", {"position_m": [*spot_m, 0.15], "pitch_rad": math.pi / 2, "moving_time_s": 1.5})
        ready_idle(server)
        page.click("#click-mode button[data-mode='grab']")
        page.evaluate("window.armlab.log.clear()")
        previous = (server.get("/api/status").get("job") or {}).get("id")
        page.mouse.click(*canvas_point(page, u, v))
        # Refused before moving (the descent to the board is checked) or a job that fails: either way it says why.
        page.locator(".toast[data-level='error']", has_text="grab").first.wait_for(timeout=30_000)
        message = page.locator(".toast[data-level='error']", has_text="grab").first.text_content()
        status = ready_idle(server)
        job = status.get("job") or {}
        if job.get("id") != previous:
            assert job["name"] == "grab" and job["state"] == "failed" and "nothing" in job["message"], job
        else:
            assert "board" in message, message  # the target was the board under the arm, not the arm's depth
        assert not status["gripper"]["holding"]
        assert page.evaluate("window.armlab.live.mode") == "grab"
        assert page.errors == []
    finally:
        page.close()
