"""Extrinsic calibration on synthetic frames with a known camera pose; save/reload; bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armlab.devices.camera import Intrinsics
from armlab.vision import Calibration, CalibrationError, calibrate_extrinsics, project_grid, top_down_view
from armlab.vision.geometry import project_points
from synth import L515, look_at_pose, render_board


def test_pose_from_tags_matches_the_true_camera(cfg, board_frame, board_pose):
    color, depth = board_frame
    cal = calibrate_extrinsics(color, L515, cfg, depth_mm=depth)
    assert cal.tag_ids == (1, 2, 3, 4)
    assert cal.reprojection_error_px < 0.6
    assert np.linalg.norm(cal.camera_position_m - board_pose[:3, 3]) < 0.004
    rot_err = np.degrees(np.arccos(np.clip((np.trace(cal.T_world_camera[:3, :3].T @ board_pose[:3, :3]) - 1) / 2, -1, 1)))
    assert rot_err < 0.2
    # The depth cross-check is an independent pose (SVD fit of back-projected tag centres).
    assert cal.depth_check_error_m is not None and cal.depth_check_error_m < 0.003
    assert np.linalg.norm(cal.T_world_camera_depth[:3, 3] - board_pose[:3, 3]) < 0.01


def test_grid_projection_and_homography_agree_with_truth(cfg, board_frame, board_pose):
    color, _ = board_frame
    cal = calibrate_extrinsics(color, L515, cfg)
    assert cal.depth_check_error_m is None
    truth = project_points(board_pose, L515.K, np.zeros(5), cfg.board.grid_points_m())
    assert np.max(np.linalg.norm(project_grid(cal, cfg) - truth, axis=1)) < 1.5
    # Board homography: world (x, y) -> pixel equals full projection for z = 0 points.
    pts = cfg.board.grid_points_m()[::7]
    hom = (cal.H_image_board @ np.column_stack([pts[:, :2], np.ones(len(pts))]).T).T
    np.testing.assert_allclose(hom[:, :2] / hom[:, 2:], project_grid(cal, cfg)[::7], atol=1e-6)


def test_top_down_view_puts_tags_where_the_board_says(cfg, board_frame):
    color, _ = board_frame
    cal = calibrate_extrinsics(color, L515, cfg)
    view = top_down_view(color, cal, mm_per_px=1.0)
    assert view.shape == (650, 1000, 3)
    # Tag 1 centre (-250, -25) mm -> column 250, row 475 - (-25) = 500: dark tag cells around it, white quiet zone.
    patch = view[500 - 10 : 500 + 11, 250 - 10 : 250 + 11]
    assert patch.min() < 60 and patch.max() > 200
    assert view[310, 520].mean() == pytest.approx(150, abs=25)  # plain board between grid lines
    assert view[300, 520].mean() < 120  # the grid line y = 175 mm lies on row 300


def test_save_and_reload_round_trip(cfg, board_frame, tmp_path):
    color, depth = board_frame
    cal = calibrate_extrinsics(color, L515, cfg, depth_mm=depth)
    path = tmp_path / "cal.json"
    cal.save(path)
    again = Calibration.load(path)
    np.testing.assert_allclose(again.T_world_camera, cal.T_world_camera)
    np.testing.assert_allclose(again.K, cal.K)
    assert again.reprojection_error_px == cal.reprojection_error_px
    assert again.depth_check_error_m == cal.depth_check_error_m
    assert again.tag_ids == cal.tag_ids
    data = json.loads(path.read_text())
    data["T_world_camera"][0][0] = 2.0  # no longer a rotation
    with pytest.raises(CalibrationError, match="rigid"):
        Calibration.from_dict(data)
    del data["K"]
    with pytest.raises(CalibrationError, match="'K'"):
        Calibration.from_dict(data)
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(CalibrationError, match="cannot read"):
        Calibration.load(tmp_path / "bad.json")


def test_no_tags_wrong_size_and_empty_images_are_refused(cfg, board_frame):
    color, depth = board_frame
    with pytest.raises(CalibrationError, match="found none"):
        calibrate_extrinsics(np.full_like(color, 140), L515, cfg)
    with pytest.raises(CalibrationError, match="1280x720"):
        calibrate_extrinsics(color[:480, :640], L515, cfg)
    with pytest.raises(CalibrationError, match="empty"):
        calibrate_extrinsics(np.zeros((0, 0, 3), np.uint8), L515, cfg)
    with pytest.raises(CalibrationError, match="depth"):
        calibrate_extrinsics(color, L515, cfg, depth_mm=depth[:100])


def test_two_tags_are_not_enough(cfg, board_pose):
    color, _ = render_board(board_pose, tags={1: (-0.25, -0.025), 2: (0.25, -0.025)})
    with pytest.raises(CalibrationError, match=r"missing \[3, 4\]"):
        calibrate_extrinsics(color, L515, cfg)


def test_misplaced_tags_are_caught_not_calibrated(cfg, board_pose):
    """Tags printed at the wrong places (3 and 4 swapped) give a large reprojection error: refused."""
    color, _ = render_board(board_pose, tags={1: (-0.25, -0.025), 2: (0.25, -0.025), 3: (-0.25, 0.275), 4: (0.25, 0.275)})
    with pytest.raises(CalibrationError, match="reprojection error"):
        calibrate_extrinsics(color, L515, cfg)


def test_depth_from_another_pose_fails_the_cross_check(cfg, board_frame):
    color, _ = board_frame
    _, other_depth = render_board(look_at_pose((-0.04, 0.40, 1.08), (0.0, 0.19, 0.0)))
    with pytest.raises(CalibrationError, match="depth cross-check"):
        calibrate_extrinsics(color, L515, cfg, depth_mm=other_depth)


def test_wrong_intrinsics_are_caught(cfg, board_frame):
    color, _ = board_frame
    wrong = Intrinsics(width=1280, height=720, fx=904.0, fy=904.0, cx=560.0, cy=420.0, dist=(0.3, 0.0, 0.0, 0.0, 0.0))
    with pytest.raises(CalibrationError, match="reprojection error"):
        calibrate_extrinsics(color, wrong, cfg)
