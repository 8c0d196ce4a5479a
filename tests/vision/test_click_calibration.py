"""Calibration by clicking known points (no tags needed): 4 and 9 board points, clicked at whole
pixels where the true camera sees them, against the simulator's ground truth; bad input refused."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.vision import load_perception_config
from armlab.vision.calibration import CalibrationError
from armlab.vision.click_calibration import calibrate_from_points
from armlab.vision.evaluate import click_grid_errors
from armlab.vision.geometry import project_points

FOUR = [(x, y) for y in (-0.125, 0.425) for x in (-0.4, 0.4)]
NINE = [(x, y) for y in (-0.125, 0.15, 0.425) for x in (-0.4, 0.0, 0.4)]


@pytest.fixture(scope="module", params=[1, 2, 3])
def sim_view(request):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=request.param, camera_pose_error=True))
    cell.start()
    try:
        cell.step(0.3)
        frame, truth = cell.render(), cell.truth()
    finally:
        cell.close()
    return frame, truth


def _clicks(frame, truth, points_xy):
    """World points (N, 3) and the whole pixels an operator would click on them."""
    world = np.array([[x, y, 0.0] for x, y in points_xy])
    T_true = np.asarray(truth["camera"]["T_world_camera"])
    return np.round(project_points(T_true, frame.intrinsics.K, np.asarray(frame.intrinsics.dist), world)), world


@pytest.mark.parametrize("points", [FOUR, NINE], ids=["4 points", "9 points"])
def test_click_calibration_matches_ground_truth(sim_view, points):
    frame, truth = sim_view
    pixels, world = _clicks(frame, truth, points)
    cal, report = calibrate_from_points(pixels, world, frame.intrinsics, load_perception_config(), depth_mm=frame.depth_mm)
    camera_error_m = np.linalg.norm(cal.camera_position_m - np.asarray(truth["camera"]["T_world_camera"])[:3, 3])
    clicks = click_grid_errors(cal, truth)
    assert camera_error_m < 0.005, camera_error_m
    assert clicks.mean() < 0.0005 and clicks.max() < 0.0015, (clicks.mean(), clicks.max())
    assert report["points"] == len(points) and report["reprojection_error_px"] < 0.6  # whole-pixel clicks: ~0.3 px
    assert len(report["point_errors_px"]) == len(points) and report["depth_check_error_m"] < 0.003


def test_typed_xy_points_mean_the_board_plane(sim_view):
    frame, truth = sim_view
    pixels, world = _clicks(frame, truth, FOUR)
    cal_xy, _ = calibrate_from_points(pixels, world[:, :2], frame.intrinsics, load_perception_config())
    cal_xyz, _ = calibrate_from_points(pixels, world, frame.intrinsics, load_perception_config())
    np.testing.assert_allclose(cal_xy.T_world_camera, cal_xyz.T_world_camera, atol=1e-9)


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda px, w: (px[:3], w[:3]), "at least 4 points"),
        (lambda px, w: (px, np.array([[x, 0.1, 0.0] for x in (-0.3, -0.1, 0.1, 0.3)])), "collinear"),
        (lambda px, w: (np.array([px[0]] * 4), w), "collinear"),
        (lambda px, w: (px, w[:3]), "one world point per click"),
        (lambda px, w: (px + np.array([2000.0, 0.0]), w), "outside"),
        (lambda px, w: (px, w[[1, 0, 2, 3]]), "reproject"),
        (lambda px, w: (px.astype(float) * np.nan, w), "finite"),
        (lambda px, w: (px, w + np.array([0.0, 1.5, 0.0])), "off the board"),
    ],
    ids=["three points", "collinear world", "one pixel clicked four times", "count mismatch", "off the image", "swapped points", "nan",
         "off the board"],
)
def test_bad_clicks_are_refused_saying_why(sim_view, mutate, message):
    frame, truth = sim_view
    pixels, world = _clicks(frame, truth, FOUR)
    bad_pixels, bad_world = mutate(pixels, world)
    with pytest.raises(CalibrationError, match=message):
        calibrate_from_points(bad_pixels, bad_world, frame.intrinsics, load_perception_config())
