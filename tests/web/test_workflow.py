"""The operator's workflow in real Chromium on the simulated workcell: calibrate, click a block to
grab it (ground truth shows it lifted), click a free spot to drop it (within 10 mm of the clicked
world point), e-stop during a move (the arm stops, the UI shows estop). Takes the README's screenshot:
into a temporary folder by default, into docs/screenshot.png with ARMLAB_UPDATE_SCREENSHOT=1."""

from __future__ import annotations

import math
import os
import time

import numpy as np
import pytest

from browser_helpers import REPO, canvas_point, open_page, wait_frames

pytestmark = pytest.mark.browser

README_SCREENSHOT = REPO / "docs" / "screenshot.png"
JOB_TIMEOUT_S = 60.0
SLEEP_RAD = np.array([0.0, -1.80, 1.55, 0.8, 0.0])  # DESIGN §4


@pytest.fixture(scope="module")
def page(browser, server):
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    wait_frames(page, 2)
    yield page
    page.close()


def truth_objects(server) -> list[dict]:
    truth = server.get("/api/sim/truth")
    return truth["objects"] if isinstance(truth, dict) else truth


def truth_after(server, sim_s: float, timeout_s: float = 30.0) -> dict:
    """Ground truth once the simulation has run sim_s seconds past now: a condition on the sim clock, not a sleep."""
    start_s = server.get("/api/sim/truth")["time_s"]
    deadline = time.monotonic() + timeout_s
    while True:
        truth = server.get("/api/sim/truth")
        if truth["time_s"] >= start_s + sim_s:
            return truth
        assert time.monotonic() < deadline, f"the simulation did not advance {sim_s} s within {timeout_s} s"
        time.sleep(0.05)


def last_job_id(server) -> str | None:
    return (server.get("/api/status").get("job") or {}).get("id")


def wait_job_done(server, name: str, previous_id: str | None) -> dict:
    """Wait until a job `name` newer than `previous_id` has ended and the station is idle again;
    fails unless it succeeded. Returns the final status."""
    status = server.wait_status(
        lambda s: (s.get("job") or {}).get("id") not in (None, previous_id)
        and s["job"]["name"] == name
        and s["job"]["state"] != "running"
        and s["state"] in ("idle", "fault", "estop"),
        JOB_TIMEOUT_S,
        f"the {name} job to end",
    )
    assert status["job"]["state"] == "succeeded", f"{name} job: {status['job']}"
    assert status["state"] == "idle", f"{name}: station in {status['state']}: {status.get('detail')}"
    return status


def ensure_calibrated(page, server) -> None:
    if not server.get("/api/calibration").get("calibrated"):
        previous = last_job_id(server)
        page.click("#btn-calibrate")
        wait_job_done(server, "calibrate", previous)
    page.wait_for_function("document.getElementById('calib-badge').dataset.ok === 'true'", timeout=15_000)


def test_calibrate_button_shows_the_result(page, server):
    page.wait_for_function("!document.getElementById('btn-calibrate').disabled", timeout=15_000)
    previous = last_job_id(server)
    page.click("#btn-calibrate")
    wait_job_done(server, "calibrate", previous)
    calibration = server.get("/api/calibration")
    assert calibration["calibrated"] is True
    page.wait_for_function("document.getElementById('calib-badge').dataset.ok === 'true'", timeout=15_000)
    page.wait_for_selector("#calib-result dd[data-key='reprojection']", timeout=15_000)
    shown = page.text_content("#calib-result dd[data-key='reprojection']")
    assert shown == f"{calibration['reprojection_error_px']:.2f} px"
    camera_mm = page.text_content("#calib-result dd[data-key='camera at']")
    expected = " ".join(f"{round(v * 1000):+d}" for v in calibration["camera_position_m"])
    assert camera_mm == f"{expected} mm"
    assert page.errors == []


def test_topdown_view_hover_maps_the_board(page, server):
    ensure_calibrated(page, server)
    page.click("#view-select button[data-view='topdown']")
    page.wait_for_function("document.getElementById('live').dataset.view === 'topdown'", timeout=15_000)
    size = page.evaluate("[document.getElementById('live').width, document.getElementById('live').height]")
    assert abs(size[0] / size[1] - 1000 / 650) < 0.01  # the whole board, 1000 x 650 mm
    try:
        hover_the_top_down_view(page)
    finally:  # later tests click on the camera view
        page.click("#view-select button[data-view='color']")
        page.wait_for_function("document.getElementById('live').dataset.view === 'color'", timeout=15_000)


def hover_the_top_down_view(page) -> None:
    # Image centre → board centre (0, 150) mm; a quarter from the left and top → (-250, 312.5) mm. The readout is
    # checked against the pointer and the canvas box as they were at each mousemove the page received (recorded
    # before the page's handler runs): a layout that shifts for a moment (a CI run saw the box 16 px right and
    # 32 px down at the event only) moves the point under the pointer, and the readout must follow it.
    page.evaluate(RECORD_MOVES)
    for fx, fy, expected in ((0.5, 0.5, (0.0, 0.15)), (0.25, 0.25, (-0.25, 0.3125))):
        for _attempt in range(5):  # the aim is taken from the layout as it is now; a layout that moves later is re-aimed
            aimed = page.evaluate(CANVAS_STATE)
            x, y = topdown_point(page, fx, fy, aimed)
            page.mouse.move(1, 1)  # off the canvas first, so the move below always reaches it as a mousemove
            page.evaluate("delete document.getElementById('hover-world').dataset.positionM; window.__moves = []")
            page.mouse.move(x, y)
            page.wait_for_function("document.getElementById('hover-world').dataset.positionM !== undefined")
            x_m, y_m, _ = page.evaluate("JSON.parse(document.getElementById('hover-world').dataset.positionM)")
            moves = page.evaluate("window.__moves")
            under_pointer = [board_point_under(move) for move in moves]
            assert any(math.dist((x_m, y_m), point) < 0.005 for point in under_pointer), (x_m, y_m, under_pointer, moves)
            if moves and all(move["rect"] == aimed["rect"] for move in moves):  # the layout aimed at is the one hovered
                assert abs(x_m - expected[0]) < 0.005 and abs(y_m - expected[1]) < 0.005, (x_m, y_m, expected, moves)
                break
        else:
            raise AssertionError(f"the canvas box moved between aiming and hovering five times running: {aimed} {moves}")
    # Hovering a block's world position in the warp highlights its row in the detections list.
    page.wait_for_function("window.armlab.detections.length > 0", timeout=20_000)
    det = page.evaluate("window.armlab.detections[0]")
    page.mouse.move(*topdown_point(page, (det["position_m"][0] + 0.5) / 1.0, (0.475 - det["position_m"][1]) / 0.65))
    page.wait_for_function("document.querySelector('#det-body tr.hover') !== null", timeout=5_000)
    assert page.get_attribute("#det-body tr.hover", "data-index") == "0"


RECORD_MOVES = ("window.__moves = []; window.addEventListener('mousemove', (e) => { const c = document.getElementById('live');"
                " if (e.target !== c) return; const r = c.getBoundingClientRect(); window.__moves.push({x: e.clientX,"
                " y: e.clientY, w: c.width, h: c.height, rect: [r.x, r.y, r.width, r.height]}); }, {capture: true})")


def board_point_under(move: dict) -> tuple[float, float]:
    """The board point (x, y) m under a recorded pointer: the 1000 x 650 mm top-down image drawn in the canvas box
    with object-fit: contain (board x -500..500 mm left to right, y 475..-175 mm top to bottom)."""
    x0, y0, width, height = move["rect"]
    scale = min(width / move["w"], height / move["h"])
    fx = (move["x"] - x0 - (width - move["w"] * scale) / 2) / (move["w"] * scale)
    fy = (move["y"] - y0 - (height - move["h"] * scale) / 2) / (move["h"] * scale)
    return (-0.5 + fx * 1.0, 0.475 - fy * 0.65)


CANVAS_STATE = ("(() => { const c = document.getElementById('live'); const r = c.getBoundingClientRect();"
                " return {w: c.width, h: c.height, view: c.dataset.view, rect: [r.x, r.y, r.width, r.height]}; })()")


def topdown_point(page, fx: float, fy: float, state: dict | None = None) -> tuple[float, float]:
    """The page point at fractions (fx, fy) of the top-down image, as drawn in `state` (CANVAS_STATE; now if None)
    with object-fit: contain."""
    state = state or page.evaluate(CANVAS_STATE)
    x0, y0, width, height = state["rect"]
    scale = min(width / state["w"], height / state["h"])
    return (x0 + (width - state["w"] * scale) / 2 + state["w"] * scale * fx,
            y0 + (height - state["h"] * scale) / 2 + state["h"] * scale * fy)


def nearest_truth(objects: list[dict], position_m) -> dict:
    blocks = [o for o in objects if o.get("type", "block") == "block"]
    return min(blocks, key=lambda o: math.dist(o["position_m"][:2], position_m[:2]))


def pixel_for_world(server, target_xy_m, start_px=(640.0, 360.0)) -> tuple[float, float]:
    """The camera pixel the station maps to world point target_xy_m, by Newton steps on its own
    POST /api/pixel-to-world (so the test shares no camera model with the code under test)."""

    def world(uv) -> np.ndarray:
        return np.array(server.post("/api/pixel-to-world", {"u": float(uv[0]), "v": float(uv[1])})["position_m"][:2])

    uv = np.array(start_px, dtype=float)
    for _ in range(5):
        w = world(uv)
        jacobian = np.column_stack([(world(uv + [8.0, 0.0]) - w) / 8.0, (world(uv + [0.0, 8.0]) - w) / 8.0])
        uv = uv + np.linalg.solve(jacobian, np.asarray(target_xy_m) - w)
        if np.linalg.norm(world(uv) - target_xy_m) < 0.001:
            break
    return float(uv[0]), float(uv[1])


def free_drop_pixel(server, objects: list[dict]) -> tuple[tuple[float, float], list[float]]:
    """A camera pixel over free board within easy reach, and the world point the station maps it to."""
    candidates_m = [(-0.15, 0.10), (0.15, 0.10), (0.0, 0.20), (-0.20, 0.20), (0.20, 0.20), (0.0, 0.12)]
    for cx, cy in candidates_m:
        if all(math.dist((cx, cy), o["position_m"][:2]) > 0.08 for o in objects):
            u, v = pixel_for_world(server, (cx, cy))
            mapped = server.post("/api/pixel-to-world", {"u": u, "v": v})["position_m"]
            if all(math.dist(mapped[:2], o["position_m"][:2]) > 0.06 for o in objects):
                return (u, v), mapped
    raise AssertionError("no free drop spot found among the candidates")


def test_click_grab_lifts_the_block_and_click_drop_places_it(page, server):
    ensure_calibrated(page, server)
    page.wait_for_function("window.armlab.detections.some(d => d.is_cube)", timeout=20_000)
    status = server.get("/api/status")
    assert not status["gripper"]["holding"]

    # Aim at the cube nearest the arm's comfortable reach.
    dets = [d for d in page.evaluate("window.armlab.detections") if d["is_cube"]]
    det = min(dets, key=lambda d: abs(math.hypot(*d["position_m"][:2]) - 0.25))
    before = nearest_truth(truth_objects(server), det["position_m"])
    assert math.dist(before["position_m"][:2], det["position_m"][:2]) < 0.02

    page.click("#click-mode button[data-mode='grab']")
    x, y = canvas_point(page, *det["center_px"])
    previous = last_job_id(server)
    page.mouse.click(x, y)
    wait_job_done(server, "grab", previous)
    held = next(o for o in truth_objects(server) if o["id"] == before["id"])
    edge_m = {"large": 0.038, "small": 0.025}.get(before.get("size"), 0.038)
    assert held["position_m"][2] > edge_m / 2 + 0.02, f"block not lifted: {held}"
    assert server.get("/api/status")["gripper"]["holding"] is True
    # The UI moved on to drop mode by itself.
    page.wait_for_function("window.armlab.live.mode === 'drop'", timeout=5_000)

    (u, v), target_m = free_drop_pixel(server, truth_objects(server))
    x, y = canvas_point(page, u, v)
    previous = last_job_id(server)
    page.mouse.click(x, y)
    wait_job_done(server, "drop", previous)
    placed = next(o for o in truth_after(server, 0.5)["objects"] if o["id"] == before["id"])  # settled
    error_m = math.dist(placed["position_m"][:2], target_m[:2])
    assert error_m < 0.010, f"dropped {error_m * 1000:.1f} mm from the clicked point {target_m}: {placed}"
    assert placed["position_m"][2] < edge_m, f"block not resting on the board: {placed}"
    assert page.errors == []


def test_screenshot_of_calibrated_scene_with_detections(page, server, tmp_path):
    update_readme = os.environ.get("ARMLAB_UPDATE_SCREENSHOT") == "1"
    screenshot = README_SCREENSHOT if update_readme else tmp_path / "screenshot.png"
    ensure_calibrated(page, server)
    # Park the arm out of the camera's way so every block is seen whole.
    page.click("#btn-sleep")
    server.wait_status(
        lambda s: not s["moving"] and np.abs(np.array(s["joints_rad"]) - SLEEP_RAD).max() < 0.02, 20.0, "the sleep pose"
    )
    page.check("#layer-grid")
    page.wait_for_function(
        "window.armlab.detections.length > 0 && window.armlab.detections.every(d => !d.occluded)", timeout=20_000
    )
    page.wait_for_function("document.querySelectorAll('#det-body tr').length > 0")
    n_rows = page.eval_on_selector_all("#det-body tr", "rows => rows.length")
    assert n_rows == len(page.evaluate("window.armlab.detections"))
    # Hover a detection so the hover readout and the row highlight show in the picture.
    det = page.evaluate("window.armlab.detections[0]")
    x, y = canvas_point(page, *det["center_px"])
    page.mouse.move(x, y)
    page.wait_for_function("document.getElementById('hover-world').dataset.positionM !== undefined", timeout=10_000)
    hover_m = page.evaluate("JSON.parse(document.getElementById('hover-world').dataset.positionM)")
    # The world point under a block's centre is on top of that block.
    assert math.dist(hover_m[:2], det["position_m"][:2]) < 0.02
    frames = wait_frames(page, 1)
    wait_frames(page, frames + 3)  # frames drawn with the grid layer on
    screenshot.parent.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(screenshot))
    assert screenshot.stat().st_size > 50_000
    page.uncheck("#layer-grid")


def test_estop_during_a_move_stops_the_arm_and_shows_estop(page, server):
    status = server.get("/api/status")
    assert status["state"] == "idle"
    q_start = np.array(status["joints_rad"])
    target_rad = SLEEP_RAD if np.abs(q_start - SLEEP_RAD).max() > 0.5 else np.zeros(5)
    page.fill("#jog-time", "4")
    # Send the long move through the page's own jog path, then hit Escape mid-way.
    page.evaluate("q => window.armlab.sendJoints(q)", target_rad.tolist())
    server.wait_status(
        lambda s: np.abs(np.array(s["joints_rad"]) - q_start).max() > 0.1, 5.0, "the arm to start moving"
    )
    page.keyboard.press("Escape")
    page.wait_for_function("document.getElementById('state-badge').textContent === 'estop'", timeout=2_000)
    assert page.get_attribute("#state-badge", "data-state") == "estop"
    assert page.is_visible("#halt-banner") and "E-STOP" in page.text_content("#halt-banner")
    q_a = np.array(truth_after(server, 0.3)["arm"]["position_rad"])
    q_b = np.array(truth_after(server, 0.7)["arm"]["position_rad"])
    assert np.abs(q_b - q_a).max() < 0.01, f"arm still moving after e-stop: {q_a} -> {q_b}"
    assert np.abs(q_b - target_rad).max() > 0.1, "the move finished: the e-stop did not stop it"
    # Only reset is offered now; reset returns to idle without moving.
    page.wait_for_function("!document.getElementById('btn-reset').disabled", timeout=5_000)
    assert page.is_disabled("#btn-home")
    page.click("#btn-reset")
    page.wait_for_function("document.getElementById('state-badge').textContent === 'idle'", timeout=5_000)
    assert not page.is_visible("#halt-banner")
    q_c = np.array(server.get("/api/status")["joints_rad"])
    assert np.abs(q_c - q_b).max() < 0.01
    assert page.errors == []


def test_sim_scene_panel_sets_a_new_scene(page, server):
    status = server.get("/api/status")
    assert status["state"] == "idle" and status["backend"] == "sim"
    page.wait_for_selector("#sim-panel:not([hidden])", timeout=5_000)
    page.select_option("#sim-event", "pick_sort")
    page.select_option("#sim-level", "2")
    page.fill("#sim-seed", "11")
    page.click("#btn-sim-scene")
    page.wait_for_function(
        "[...document.querySelectorAll('#event-log li')].some(li => li.textContent.includes('scene set: pick_sort'))",
        timeout=10_000,
    )
    objects = truth_objects(server)
    assert len(objects) == 6  # pick_sort level 2: 3 large + 3 small cubes
    assert sorted(o["size"] for o in objects) == ["large"] * 3 + ["small"] * 3
    # The detections list follows the new scene.
    page.wait_for_function("document.querySelectorAll('#det-body tr').length === 6", timeout=20_000)
    assert page.errors == []
