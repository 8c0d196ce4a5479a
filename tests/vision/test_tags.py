"""Tag detection on synthetic boards with exact corner positions."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from armlab.vision import detect_tags
from armlab.vision.geometry import project_points
from synth import L515, look_at_pose, render_board


def _true_corners(cfg, pose, tag_id):
    return project_points(pose, L515.K, np.zeros(5), cfg.board_tag_corners_m(tag_id))


def test_finds_the_four_board_tags_with_subpixel_corners_in_world_order(cfg, board_frame, board_pose):
    tags = detect_tags(board_frame[0], cfg)
    assert [t.id for t in tags] == [1, 2, 3, 4]
    for tag in tags:
        truth = _true_corners(cfg, board_pose, tag.id)
        # Same order as the world corners (TL, TR, BR, BL seen from above with +y up) and sub-pixel close.
        assert np.max(np.linalg.norm(tag.corners_px - truth, axis=1)) < 0.8
        np.testing.assert_allclose(tag.center_px, truth.mean(axis=0), atol=0.5)


def test_first_corner_is_the_tags_plus_y_minus_x_corner(cfg, board_frame, board_pose):
    """Catches a texture/config mismatch: rotated tags would put corner 0 elsewhere."""
    tag = detect_tags(board_frame[0], cfg)[0]
    corner0_world = cfg.board_tag_corners_m(tag.id)[0]
    centre_world = np.array([*cfg.tags.board_tags[tag.id], 0.0])
    assert corner0_world[0] < centre_world[0] and corner0_world[1] > centre_world[1]
    assert np.linalg.norm(tag.corners_px[0] - _true_corners(cfg, board_pose, tag.id)[0]) < 1.0


@pytest.mark.parametrize("position_m", [(0.25, 0.5, 0.8), (-0.2, -0.15, 0.85), (0.0, 0.125, 0.95)])
def test_tilted_and_shaded_views(cfg, position_m):
    pose = look_at_pose(position_m, (0.0, 0.125, 0.0))  # up to ~30 degrees of tilt
    for tag_id in (1, 2, 3, 4):  # precondition: every tag is inside the image
        px = _true_corners(cfg, pose, tag_id)
        assert np.all((px > 0) & (px < [1280, 720]))
    color, _ = render_board(pose, shade=True)
    tags = detect_tags(color, cfg)
    assert [t.id for t in tags] == [1, 2, 3, 4]
    for tag in tags:
        assert np.max(np.linalg.norm(tag.corners_px - _true_corners(cfg, pose, tag.id), axis=1)) < 1.0


def test_small_tags_far_away(cfg):
    pose = look_at_pose((-0.04, 0.40, 1.35), (0.0, 0.15, 0.0))  # tags ~16 px wide
    color, _ = render_board(pose)
    tags = detect_tags(color, cfg)
    assert [t.id for t in tags] == [1, 2, 3, 4]
    assert max(np.ptp(t.corners_px[:, 0]) for t in tags) < 18


def test_other_dictionary_by_name(cfg):
    aruco = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    marker = cv2.aruco.generateImageMarker(aruco, 7, 120)
    image = np.full((480, 640, 3), 255, np.uint8)
    image[100:220, 200:320] = marker[:, :, None]
    assert detect_tags(image, cfg) == []  # the default 36h11 dictionary does not decode a 4x4 marker
    tags = detect_tags(image, cfg, dictionary="DICT_4X4_50")
    assert [t.id for t in tags] == [7]
    np.testing.assert_allclose(tags[0].corners_px[0], [199.5, 99.5], atol=1.0)


def test_bad_images_are_refused(cfg):
    with pytest.raises(ValueError, match="empty"):
        detect_tags(np.zeros((0, 0, 3), np.uint8), cfg)
    with pytest.raises(ValueError, match="uint8"):
        detect_tags(np.zeros((100, 100, 3), np.float32), cfg)
    with pytest.raises(ValueError, match="shape"):
        detect_tags(np.zeros((100, 100, 4), np.uint8), cfg)
    with pytest.raises(ValueError, match="unknown"):
        detect_tags(np.zeros((100, 100, 3), np.uint8), cfg, dictionary="DICT_NOPE")
    assert detect_tags(np.full((720, 1280, 3), 128, np.uint8), cfg) == []


def test_tags_half_in_hard_shadow(cfg, board_frame, board_pose):
    """A shadow edge (60 % darker) running through every tag: still found, corners still sub-pixel-ish."""
    color = board_frame[0].copy()
    for tag_id in (1, 2, 3, 4):
        px = _true_corners(cfg, board_pose, tag_id)
        x0, y0 = px.min(axis=0).astype(int) - 8
        xm, y1 = int(px[:, 0].mean()), px.max(axis=0).astype(int)[1] + 8
        color[y0:y1, x0:xm] = (color[y0:y1, x0:xm] * 0.4).astype(np.uint8)
    tags = detect_tags(color, cfg)
    assert [t.id for t in tags] == [1, 2, 3, 4]
    for tag in tags:
        assert np.max(np.linalg.norm(tag.corners_px - _true_corners(cfg, board_pose, tag.id), axis=1)) < 1.5
