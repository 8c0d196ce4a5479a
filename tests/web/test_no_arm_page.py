"""The page of a station with no arm on a real recorded frame: `armlab serve --camera recorded --source
../shared/data/rob550_dev --frame blocks --arm none` (real subprocess, real Chromium). The real frame is shown,
Calibrate from the page works on its real tags, a click on a real labelled cube reads its world position (its
pixel -> world through the calibration at the label's height, and that height from depth), and the arm's
buttons are blocked with the reason, which the server also gives when asked anyway. One server, one page."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from browser_helpers import canvas_point, open_page, wait_frames
from conftest import running_server

pytestmark = pytest.mark.browser

DEV = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "rob550_dev"
FRAME = "blocks"
XY_TOLERANCE_M = 0.006  # the click lands within ~1 px of the label (~1.1 mm at 1 m); labels are centroids by eye/depth
HEIGHT_TOLERANCE_M = 0.006  # real depth: the board plane sits ~10 mm off the tags' plane, tilted ~1.5° (issue 17)

if not DEV.is_dir():
    pytest.skip(f"the real ROB 550 development frames are not on this machine (looked in {DEV})", allow_module_level=True)


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    args = ("--camera", "recorded", "--source", str(DEV), "--frame", FRAME, "--arm", "none")
    with running_server(tmp_path_factory.mktemp("no_arm"), args) as srv:
        yield srv


def _cube_label() -> dict:
    """A large cube standing on the board, labelled with certainty, from the frame's hand labels."""
    labels = json.loads((DEV / f"image_{FRAME}.labels.json").read_text())
    return next(c for c in labels["cubes"] if c["size"] == "large" and not c["stacked_on_another"] and not c.get("uncertain"))


def _pixel_to_world_at_height(calibration: dict, u: float, v: float, height_m: float) -> np.ndarray:
    """The world point where the ray through pixel (u, v) meets the plane z = height_m: the test's own
    pinhole model (OpenCV undistortion) with the calibration's K, distortion and camera pose."""
    K, dist = np.asarray(calibration["K"], float), np.asarray(calibration["dist"], float)
    T = np.asarray(calibration["T_world_camera"], float)
    x, y = cv2.undistortPoints(np.array([[[u, v]]], float), K, dist).reshape(2)
    origin, direction = T[:3, 3], T[:3, :3] @ np.array([x, y, 1.0])
    return origin + direction * (height_m - origin[2]) / direction[2]


def test_a_real_frame_calibrates_reads_a_cube_and_refuses_the_arm(station, browser):
    page = open_page(browser, f"{station.base_url}/?token={station.token}")
    try:
        wait_frames(page, 2)
        # The real frame: the canvas is the recording's size, and a patch away from every overlay is its colour.
        size = page.eval_on_selector("#live", "c => [c.width, c.height]")
        assert size == [1280, 720]
        patch = page.evaluate("() => Array.from(document.getElementById('live').getContext('2d').getImageData(20, 20, 40, 40).data)")
        rgba = np.asarray(patch, float).reshape(-1, 4)
        expected_bgr = cv2.imread(str(DEV / f"image_{FRAME}.png"))[20:60, 20:60].reshape(-1, 3).mean(axis=0)
        assert np.abs(rgba[:, 2::-1].mean(axis=0) - expected_bgr).max() < 12  # JPEG on the way

        # The arm's panels and buttons say why they are off; the server refuses the same with the reason.
        home = page.eval_on_selector("#btn-home", "b => ({disabled: b.disabled, title: b.title})")
        assert home["disabled"] and "no arm" in home["title"]
        for selector in ("#btn-teach-start", "#btn-comp-start", "#btn-send-joints", "[data-mode=grab]", "[data-jog='x+']"):
            assert page.eval_on_selector(selector, "b => b.disabled"), selector
        note = page.inner_text("#arm-panel .no-arm-note")
        assert "no arm" in note and page.is_visible("#arm-panel .no-arm-note")
        refusal = page.evaluate(
            "() => window.armlab.api.post('/api/arm/home', {}).then(() => null, (e) => ({status: e.status, code: e.code, message: e.message}))"
        )
        assert refusal["status"] == 409 and refusal["code"] == "no_arm" and "this station has no arm" in refusal["message"]

        # Calibrate from the page on the real tags (tagStandard41h12: found by the board choice at start-up).
        page.click("#btn-calibrate")
        page.wait_for_function("document.getElementById('calib-badge').dataset.ok === 'true'", timeout=30000)
        calibration = station.get("/api/calibration")
        assert calibration["calibrated"] and calibration["reprojection_error_px"] < 1.5

        # A click on a real cube: the readout is its world position.
        cube = _cube_label()
        x, y = canvas_point(page, cube["u"], cube["v"])
        page.mouse.click(x, y)
        page.wait_for_function("Boolean(document.getElementById('hover-world').dataset.pixel)", timeout=10000)
        position_m = np.asarray(json.loads(page.get_attribute("#hover-world", "data-position-m")))
        u, v, depth_mm = json.loads(page.get_attribute("#hover-world", "data-pixel"))
        assert abs(u - cube["u"]) <= 1.5 and abs(v - cube["v"]) <= 1.5 and depth_mm > 0
        height_m = cube["depth_height_mm"] / 1000.0
        expected_m = _pixel_to_world_at_height(calibration, cube["u"], cube["v"], height_m)
        assert np.linalg.norm(position_m[:2] - expected_m[:2]) < XY_TOLERANCE_M, (position_m, expected_m)
        assert abs(position_m[2] - height_m) < HEIGHT_TOLERANCE_M, (position_m[2], height_m)
        assert page.errors == []
    finally:
        page.close()
