"""Calibration by clicking known points, from the page (issue 11 item 3): the operator picks board grid
corners offered by the page (the workcell grid from the server's hello), clicks each where it is on the
live video, and fits; the station's calibration is then checked against the simulation's ground truth
(the true camera pose and intrinsics: camera position error, click-to-world error of grid points not
clicked). Below 4 points Fit is disabled ("click at least 4 points"); collinear points and a point off
the board are refused on the page with the reason, and the old calibration is kept. Also the self-recalibration toggle (PUT /api/calibration/settings)."""

from __future__ import annotations

import cv2
import httpx
import numpy as np
import pytest

from browser_helpers import canvas_point, open_page, wait_frames
from conftest import running_server

pytestmark = pytest.mark.browser

# Grid corners (m) spread over the board, away from the arm's base and the scene's blocks.
NINE = [(-0.40, 0.425), (0.0, 0.425), (0.40, 0.425), (-0.40, 0.125), (0.0, 0.175), (0.40, 0.125),
        (-0.40, -0.125), (-0.20, -0.125), (0.40, -0.125)]
ROW = [(-0.40, 0.425), (-0.15, 0.425), (0.15, 0.425), (0.40, 0.425)]  # all on one line
CHECK = [(-0.30, 0.325), (0.30, 0.325), (0.25, 0.025), (-0.25, 0.025), (0.0, 0.325)]  # not clicked


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    with running_server(tmp_path_factory.mktemp("click_calibration")) as srv:
        yield srv


def true_pixel(camera: dict, xy_m) -> tuple[float, float]:
    """Where board point xy_m is in the image: the simulation's true camera pose and intrinsics."""
    T_camera_world = np.linalg.inv(np.asarray(camera["T_world_camera"]))
    rvec = cv2.Rodrigues(T_camera_world[:3, :3])[0]
    uv, _ = cv2.projectPoints(np.array([[xy_m[0], xy_m[1], 0.0]]), rvec, T_camera_world[:3, 3],
                              np.asarray(camera["K"]), np.asarray(camera["dist"], dtype=float))
    return float(uv[0, 0, 0]), float(uv[0, 0, 1])


def board_point(calibration: dict, uv) -> np.ndarray:
    """The board point (z = 0) the station's calibration puts under pixel uv (its own K and dist)."""
    K, dist = np.asarray(calibration["K"]), np.asarray(calibration["dist"])
    x, y = cv2.undistortPoints(np.array([[uv]], dtype=float), K, dist).ravel()
    T = np.asarray(calibration["T_world_camera"])
    ray = T[:3, :3] @ np.array([x, y, 1.0])
    return (T[:3, 3] + ray * (-T[2, 3] / ray[2]))[:2]


def choose_corner(page, xy_m) -> None:
    """Pick the grid corner in the page's x and y lists (the values the server's grid offers)."""
    for select, value in (("#clickcal-x", xy_m[0]), ("#clickcal-y", xy_m[1])):
        chosen = page.evaluate(
            """([sel, v]) => {
                const s = document.querySelector(sel);
                const o = [...s.options].find((o) => Math.abs(Number(o.value) - v) < 1e-6);
                if (o) { s.value = o.value; }
                return Boolean(o);
            }""", [select, value])
        assert chosen, f"the page offers no grid corner at {value} m in {select}"


def click_points(page, camera, points) -> None:
    for xy in points:
        choose_corner(page, xy)
        page.mouse.click(*canvas_point(page, *true_pixel(camera, xy)))
    page.wait_for_function(f"document.querySelectorAll('#clickcal-points tr').length === {len(points)}")


def fit_refused(page, server, words: str) -> str:
    before = server.get("/api/calibration")
    page.click("#btn-clickcal-fit")
    page.wait_for_function("!document.getElementById('clickcal-error').hidden", timeout=30_000)
    message = page.text_content("#clickcal-error")
    assert words in message and "old calibration is kept" in message, message
    assert server.get("/api/calibration") == before  # nothing changed
    page.click("#btn-clickcal-clear")
    return message


def fit_blocked(page, server, clicked: int) -> None:
    """Below 4 points Fit is disabled and says to click at least 4 points; a click on it sends nothing."""
    page.wait_for_function("document.getElementById('btn-clickcal-fit').textContent.includes('at least 4')")
    fit = page.query_selector("#btn-clickcal-fit")
    assert fit.is_disabled() and "click at least 4 points" in fit.text_content(), fit.text_content()
    assert page.eval_on_selector_all("#clickcal-points tr", "rows => rows.length") == clicked
    before = server.get("/api/calibration")
    fit.click(force=True)  # a disabled button ignores it: no request, no raw 422 shown
    assert page.is_hidden("#clickcal-error") and page.is_disabled("#btn-clickcal-fit")
    assert server.get("/api/calibration") == before


def test_click_calibration_from_the_page_matches_ground_truth(browser, fresh):
    page = open_page(browser, f"{fresh.base_url}/?token={fresh.token}")
    wait_frames(page, 2)
    camera = fresh.get("/api/sim/truth")["camera"]
    assert not fresh.get("/api/status")["calibrated"]
    page.click("#click-mode button[data-mode='points']")
    page.wait_for_function("document.getElementById('clickcal').open && document.getElementById('clickcal-x').options.length > 10")

    fit_blocked(page, fresh, 0)
    click_points(page, camera, NINE[:3])
    fit_blocked(page, fresh, 3)
    page.click("#btn-clickcal-clear")
    click_points(page, camera, ROW)  # four points: Fit is enabled again (page.click waits for that)
    fit_refused(page, fresh, "collinear")
    page.fill("#clickcal-typed", "900, 100")  # typed, but off the 1000 mm board
    page.mouse.click(*canvas_point(page, 640, 360))
    assert "off the board" in page.text_content("#clickcal-error")
    assert page.eval_on_selector_all("#clickcal-points tr", "rows => rows.length") == 0  # not added
    page.fill("#clickcal-typed", "")

    click_points(page, camera, NINE)
    page.click("#btn-clickcal-fit")
    page.wait_for_selector("#clickcal-result dd[data-key='reprojection']", timeout=30_000)
    assert page.is_hidden("#clickcal-error")
    residuals = page.eval_on_selector_all("#clickcal-points tr td:last-child", "cells => cells.map((c) => Number(c.textContent))")
    assert len(residuals) == 9 and all(0 <= r < 1.5 for r in residuals), residuals

    status = fresh.wait_status(lambda s: s["calibrated"] and s["state"] == "idle", 10.0, "calibrated")
    assert status["calibration_state"] == "trusted"
    calibration = fresh.get("/api/calibration")
    assert calibration["method"] == "points" and calibration["points"]["points"] == 9
    truth_T = np.asarray(camera["T_world_camera"])
    position_error_m = float(np.linalg.norm(np.asarray(calibration["camera_position_m"]) - truth_T[:3, 3]))
    click_to_world_m = [float(np.linalg.norm(board_point(calibration, true_pixel(camera, xy)) - xy)) for xy in CHECK]
    print(f"click calibration from the page, 9 points: camera position error {position_error_m * 1000:.1f} mm, "
          f"click-to-world {np.mean(click_to_world_m) * 1000:.2f} mm mean, {max(click_to_world_m) * 1000:.2f} mm max, "
          f"residuals {residuals} px")
    assert position_error_m < 0.010, position_error_m
    assert max(click_to_world_m) < 0.002, click_to_world_m
    assert page.errors == []
    page.close()


def test_self_recalibration_toggle_sets_the_station(browser, fresh):
    page = open_page(browser, f"{fresh.base_url}/?token={fresh.token}")
    wait_frames(page, 1)
    page.wait_for_function("window.armlab.status !== null")
    assert not page.is_checked("#self-recal") and fresh.get("/api/calibration/settings")["self_recalibrate"] is False
    page.check("#self-recal")
    fresh.wait_status(lambda s: s["self_recalibrate"] is True, 10.0, "self-recalibration on")
    assert fresh.get("/api/calibration/settings")["self_recalibrate"] is True
    fresh.request("PUT", "/api/calibration/settings", json={"self_recalibrate": False}).raise_for_status()
    page.wait_for_function("!document.getElementById('self-recal').checked", timeout=10_000)  # the status says so
    assert fresh.request("PUT", "/api/calibration/settings", json={"self_recalibrate": "yes"}).status_code == 422
    no_token = httpx.put(fresh.base_url + "/api/calibration/settings", json={"self_recalibrate": True}, timeout=10.0)
    assert no_token.status_code == 401 and fresh.get("/api/calibration/settings")["self_recalibrate"] is False
    assert page.errors == []
    page.close()
