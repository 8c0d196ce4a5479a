"""Overlay layers (each switchable, input untouched) and depth-only objects on synthetic frames."""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
import pytest

from armlab.vision import (
    Block,
    OverlayLayers,
    calibrate_extrinsics,
    detect_objects_from_depth,
    detect_tags,
    draw_overlay,
    project_grid,
)
from armlab.vision.objects import fit_plane_ransac
from synth import L515


@pytest.fixture(scope="module")
def cal(cfg, board_frame):
    return calibrate_extrinsics(board_frame[0], L515, cfg)


def _block(cal):
    from armlab.vision import world_to_pixel

    centre = np.array([0.1, 0.2, 0.038])
    corners = world_to_pixel(cal, centre + np.array([[-0.019, 0.019, 0], [0.019, 0.019, 0], [0.019, -0.019, 0], [-0.019, -0.019, 0]]))
    return Block("red", "large", centre, 0.2, 0.038, 1, corners.mean(axis=0), corners)


def test_each_layer_draws_only_itself(cfg, board_frame, cal):
    color = board_frame[0]
    before = color.copy()
    tags = detect_tags(color, cfg)
    blocks = [_block(cal)]
    none = draw_overlay(color, tags, blocks, cal, OverlayLayers(tags=False, detections=False, grid=False, labels=False))
    np.testing.assert_array_equal(none, color)
    grid_only = draw_overlay(color, tags, blocks, cal, OverlayLayers(tags=False, detections=False, grid=True))
    changed = np.any(grid_only != color, axis=2)
    u, v = np.round(project_grid(cal, cfg)[100]).astype(int)
    assert changed[v, u]  # a projected grid point is painted
    tag_layer = draw_overlay(color, tags, blocks, cal, OverlayLayers(tags=True, detections=False, grid=False))
    changed_tags = np.any(tag_layer != color, axis=2)
    ys, xs = np.nonzero(changed_tags)
    # Tag outlines: every painted pixel is near a tag (labels included).
    near_tag = [min(np.linalg.norm(t.center_px - [x, y]) for t in tags) < 40 for x, y in zip(xs[::50], ys[::50])]
    assert all(near_tag) and len(near_tag) > 0
    det = draw_overlay(color, tags, blocks, cal, OverlayLayers(tags=False, detections=True, grid=False, labels=False))
    changed_det = np.any(det != color, axis=2)
    assert changed_det[int(blocks[0].center_px[1]), int(blocks[0].center_px[0])]  # centre dot
    labelled = draw_overlay(color, tags, blocks, cal, OverlayLayers(tags=False, detections=True, grid=False, labels=True))
    assert np.count_nonzero(np.any(labelled != color, axis=2)) > np.count_nonzero(changed_det)  # the label text
    np.testing.assert_array_equal(color, before)  # the input frame is never drawn on


def test_objects_from_depth_on_a_synthetic_table(cfg, board_frame, cal, board_pose):
    """Two boxes of 40 and 60 mm pushed into an exact plane depth image: found with the right heights."""
    depth = board_frame[1].copy()
    K = L515.K
    for (x, y, size, height) in [(0.1, 0.2, 0.04, 0.04), (-0.2, 0.05, 0.03, 0.06)]:
        # Rasterise the box top: pixels whose board point lies under the top face get the top's depth.
        u, v = np.meshgrid(np.arange(1280), np.arange(720))
        rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones_like(u, float)], axis=-1)
        d_world = rays @ board_pose[:3, :3].T
        s = (height - board_pose[2, 3]) / d_world[..., 2]
        hit = board_pose[:3, 3] + d_world * s[..., None]
        inside = (np.abs(hit[..., 0] - x) < size / 2) & (np.abs(hit[..., 1] - y) < size / 2)
        depth[inside] = np.round(s[inside] * 1000).astype(np.uint16)
    objects = detect_objects_from_depth(depth, cal, cfg)
    assert len(objects) == 2
    by_x = sorted(objects, key=lambda o: o.centroid_m[0])
    assert by_x[0].height_m == pytest.approx(0.06, abs=0.003)
    assert by_x[1].height_m == pytest.approx(0.04, abs=0.003)
    np.testing.assert_allclose(by_x[1].centroid_m[:2], (0.1, 0.2), atol=0.004)
    assert by_x[1].extent_m[0] == pytest.approx(0.04, abs=0.005)


def test_plane_fit_and_bad_depth(cfg, cal):
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(-1, 1, 500), rng.uniform(-1, 1, 500), np.full(500, 0.9)])
    pts[:100, 2] -= rng.uniform(0.02, 0.1, 100)  # clutter above the table (toward the camera)
    normal, d, inliers = fit_plane_ransac(pts, 100, 0.002, seed=1)
    assert abs(normal[2]) == pytest.approx(1.0, abs=1e-6) and inliers.sum() == 400
    with pytest.raises(ValueError, match="too few valid"):
        detect_objects_from_depth(np.zeros((720, 1280), np.uint16), cal, cfg)
    with pytest.raises(ValueError, match="depth must be"):
        detect_objects_from_depth(np.zeros((10, 10), np.uint16), cal, cfg)


def test_a_blocks_outline_is_drawn_within_a_pixel_of_its_contour(cfg, board_frame, cal):
    """The overlay draws a block's contour through its corners that matter (OUTLINE_TOLERANCE_PX): every point
    of the contour lies within that of the drawn polygon, which has far fewer corners than a pixel staircase,
    and the drawing covers the contour."""
    from armlab.vision.overlay import OUTLINE_TOLERANCE_PX, outline_px

    mask = np.zeros((120, 160), np.uint8)
    cv2.ellipse(mask, (80, 60), (37, 21), 17.0, 0, 360, 1, -1)  # a tilted face: a long pixel staircase
    contour = max(cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0], key=cv2.contourArea).reshape(-1, 2) + [600, 300]
    polygon = outline_px(contour.astype(np.float64))
    assert 4 <= len(polygon) <= len(contour) // 2
    distances = [abs(cv2.pointPolygonTest(polygon, (float(x), float(y)), True)) for x, y in contour]
    assert max(distances) <= OUTLINE_TOLERANCE_PX
    block = replace(_block(cal), contour_px=contour.astype(np.float64), center_px=contour.mean(axis=0))
    color = board_frame[0]
    drawn = np.any(draw_overlay(color, [], [block], cal, OverlayLayers(tags=False, detections=True, grid=False, labels=False)) != color, axis=2)
    assert all(drawn[y, x] or drawn[y - 1 : y + 2, x - 1 : x + 2].any() for x, y in contour)
