"""The pure helpers the perception pass's speed-ups rely on (issue 17, per-frame time): each must give
exactly what it replaces, and its memory must never hand back another input's answer; and the detector as
a whole must report on the real frames what it reported before them."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from armlab.kinematics.arm_model import load_arm
from armlab.vision import calibrate_extrinsics
from armlab.vision.block_geometry import STEP, BlockGeometry
from armlab.vision.block_pixels import components, pixels_of
from armlab.vision.board_plane import fit_board_plane
from armlab.vision.colors import (
    BOARD_CHROMATICITY_BAND,
    BOARD_LUMINANCE_BAND,
    BOARD_MAX_SATURATION,
    CLIP_MARGIN,
    CLIP_TOP_PIXELS,
    CLIPPED,
    MIN_BOARD_PIXELS,
    MIN_CLIP_LEVEL,
    ColorModel,
    board_reference_bgr,
    board_region_mask,
    channel_medians,
    frame_clip_levels_rgb,
)
from armlab.vision.face_shape import _nearest_centre
from armlab.vision.geometry import inverse_homography, project_points
from armlab.vision.self_filter import RobotSelfFilter, _in_box, _in_capsule, _RayGrid, robot_mask
from rob550_dev import DEV, needs_dev_frames


@pytest.mark.parametrize("count", [1, 2, 3, 4, 511, 512, 1000])
def test_channel_medians_are_numpys_medians_odd_and_even(count):
    pixels = np.random.default_rng(count).integers(0, 256, (count, 3)).astype(np.uint8)
    medians = channel_medians(pixels)
    assert medians.dtype == np.float64
    np.testing.assert_array_equal(medians, np.median(pixels, axis=0))  # an even count: the mean of the middle two


def test_channel_medians_keep_the_channels_apart():
    pixels = np.array([[10, 200, 30], [12, 190, 31], [11, 210, 29]], np.uint8)
    np.testing.assert_array_equal(channel_medians(pixels), [11.0, 200.0, 30.0])


def test_inverse_homography_follows_the_array_it_is_given():
    rng = np.random.default_rng(4)
    first, second = np.eye(3) + 0.1 * rng.normal(size=(3, 3)), np.eye(3) + 0.1 * rng.normal(size=(3, 3))
    inverse_first = inverse_homography(first)
    np.testing.assert_allclose(inverse_first @ first, np.eye(3), atol=1e-12)
    assert inverse_homography(first) is inverse_first  # remembered for the same array
    np.testing.assert_allclose(inverse_homography(second) @ second, np.eye(3), atol=1e-12)  # never the last one's
    np.testing.assert_allclose(inverse_homography(first.copy()) @ first, np.eye(3), atol=1e-12)


def test_the_colour_model_of_a_config_is_its_own(cfg):
    model = ColorModel.from_config(cfg)
    assert ColorModel.from_config(cfg) is model  # built once per (frozen) section
    other_section = cfg.color_model.model_copy(update={"max_distance": 3.0})
    other = ColorModel.from_config(other_section)
    assert other.max_distance == 3.0 and model.max_distance == cfg.color_model.max_distance
    assert ColorModel.from_config(cfg).max_distance == cfg.color_model.max_distance


def test_board_region_per_calibration_is_the_projected_board(cfg, board_frame, intrinsics):
    color, depth = board_frame
    cal = calibrate_extrinsics(color, intrinsics, cfg, depth_mm=depth)
    geometry = BlockGeometry(cal, cfg)
    region = geometry.board_region(cfg.board.x_range_m, cfg.board.y_range_m)
    expected = board_region_mask(geometry.small_shape, cal.T_world_camera, cal.K, cal.dist, cfg.board.x_range_m, cfg.board.y_range_m, STEP)
    np.testing.assert_array_equal(region, expected)
    assert 0 < np.count_nonzero(region) < region.size
    assert geometry.board_region(cfg.board.x_range_m, cfg.board.y_range_m) is region
    assert not region.flags.writeable


# --- issue 17, second round: each cheaper formulation against the one it replaced, and the detector as a whole ---

DETECTIONS = Path(__file__).parent / "data" / "rob550_dev_detections.json"


def _summary(block) -> dict:
    """A detection as tests/vision/data/rob550_dev_detections.json holds it (rounded well past the figures the
    benches report, so other CPUs' last-bit differences do not show, while a changed detection does)."""
    return {"color": block.color, "size": block.size, "cube": bool(block.is_cube), "occluded": bool(block.occluded),
            "level": int(block.stack_level), "tag": block.aruco_id, "centre_px": [round(float(x), 2) for x in block.center_px],
            "position_mm": [round(float(x) * 1000, 2) for x in block.position_m], "yaw_deg": round(float(np.degrees(block.yaw_rad)), 2),
            "side_mm": round(float(block.side_m) * 1000, 2),
            "lab": None if block.color_lab is None else [round(float(x), 1) for x in block.color_lab]}


@needs_dev_frames
def test_the_real_frames_give_the_detections_of_the_detector_before_the_speedups():
    """Every detection on the eight real ROB 550 frames, every field, as the detector gave them before this round
    of speed-ups (commit 68efa2f, bench/real_frames.py's pass): an optimisation that changes what is reported fails here."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
    from real_frames import intrinsics_for, perception_config

    from armlab.vision import detect_tags
    from armlab.vision.pipeline import PerceptionPipeline
    from armlab.vision.rgbd_files import read_color, read_depth

    expected = json.loads(DETECTIONS.read_text())
    cfg = perception_config("rob550")
    for name, blocks in expected.items():
        color = read_color(DEV / f"image_{name}.png")
        depth = read_depth(DEV / f"depth_{name}.png", (color.shape[1], color.shape[0]))
        intr, _ = intrinsics_for(DEV, name, color.shape[1], color.shape[0])
        cal = calibrate_extrinsics(color, intr, cfg, depth_mm=depth, tags=detect_tags(color, cfg))
        found = [_summary(b) for b in PerceptionPipeline(cfg).process(color, depth, cal, layers=None).blocks]
        assert found == blocks, name


def test_pixels_of_is_nonzero_in_row_major_order():
    mask = np.random.default_rng(3).random((37, 53)) > 0.6
    flat, ys, xs = pixels_of(mask)
    rows, cols = np.nonzero(mask)
    np.testing.assert_array_equal(ys, rows)
    np.testing.assert_array_equal(xs, cols)
    np.testing.assert_array_equal(flat, rows * 53 + cols)


def test_components_on_the_set_pixels_window_are_the_whole_images():
    rng = np.random.default_rng(5)
    masks = [np.zeros((180, 320), np.uint8)]
    for _ in range(60):
        mask = np.zeros((180, 320), np.uint8)
        for _ in range(int(rng.integers(1, 12))):  # blobs with corners on odd and even rows and columns
            x, y = int(rng.integers(0, 318)), int(rng.integers(0, 178))
            mask[y : y + int(rng.integers(1, 25)), x : x + int(rng.integers(1, 25))] = 1
        mask[rng.random((180, 320)) > 0.995] = 1
        masks.append(mask)
    for mask in masks:
        n, labels, stats = components(mask)
        n_ref, labels_ref, stats_ref, _ = cv2.connectedComponentsWithStatsWithAlgorithm(mask, 8, cv2.CV_32S, cv2.CCL_GRANA)
        assert n == n_ref
        assert stats[1:] == stats_ref[1:].tolist()
        x0, y0 = stats[0][:2]
        window = labels_ref[y0 : y0 + labels.shape[0], x0 : x0 + labels.shape[1]]
        np.testing.assert_array_equal(labels, window)
        assert np.count_nonzero(labels_ref) == np.count_nonzero(window)  # no label outside the window


def _board_reference_bgr_before(color_bgr: np.ndarray, board_mask: np.ndarray) -> np.ndarray:
    """board_reference_bgr as it was written before (boolean indexing, int32 channels, one median at a time)."""
    pixels = color_bgr[board_mask.astype(bool)]
    if len(pixels) < MIN_BOARD_PIXELS:
        raise ValueError("few")
    b, g, r = (pixels[:, channel].astype(np.int32) for channel in range(3))
    hi, lo = np.maximum(np.maximum(b, g), r), np.minimum(np.minimum(b, g), r)
    is_grey = (hi - lo) * 255 <= BOARD_MAX_SATURATION * np.maximum(hi, 1)
    if np.count_nonzero(is_grey) < MIN_BOARD_PIXELS:
        raise ValueError("few grey")
    grey = np.stack([b[is_grey], g[is_grey], r[is_grey]]).astype(np.float32)
    total = grey[0] + grey[1] + grey[2]
    blue, red = grey[0] / np.maximum(total, 1.0), grey[2] / np.maximum(total, 1.0)

    def median(values):
        return float(np.partition(values, values.size // 2)[values.size // 2])

    keep = np.ones(total.size, bool)
    for _ in range(2):
        m = median(total[keep])
        keep = ((np.abs(total - m) <= BOARD_LUMINANCE_BAND * max(m, 3.0)) & (np.abs(blue - median(blue[keep])) <= BOARD_CHROMATICITY_BAND)
                & (np.abs(red - median(red[keep])) <= BOARD_CHROMATICITY_BAND))
        if np.count_nonzero(keep) < MIN_BOARD_PIXELS:
            raise ValueError("no dominant grey")
    return np.array([median(grey[channel][keep]) for channel in range(3)], dtype=float)


def test_board_reference_bgr_matches_its_direct_formulation(board_frame):
    color, _ = board_frame
    rng = np.random.default_rng(11)
    small = cv2.resize(color, (320, 180), interpolation=cv2.INTER_NEAREST)
    noisy = np.clip(small.astype(int) + rng.integers(-40, 40, small.shape), 0, 255).astype(np.uint8)
    for image in (small, noisy):
        for _ in range(40):
            y, x = int(rng.integers(0, 140)), int(rng.integers(0, 280))
            window, mask = image[y : y + 49 : 2, x : x + 49 : 2], (rng.random((180, 320)) > 0.3)[y : y + 49 : 2, x : x + 49 : 2]
            try:
                expected = _board_reference_bgr_before(window, mask)
            except ValueError:
                with pytest.raises(ValueError):
                    board_reference_bgr(window, mask)
                continue
            np.testing.assert_array_equal(board_reference_bgr(window, mask), expected)


def _clip_test_images(color: np.ndarray, rng) -> list[np.ndarray]:
    """Frames from dark to overexposed, and planes whose CLIP_TOP_PIXELS-th brightest value lies far below
    their brightest (a few hot pixels), exactly at it, or just short of a level."""
    images = [np.clip(color.astype(float) * scale + rng.normal(0, 3, color.shape), 0, 255).astype(np.uint8)[::4, ::4]
              for scale in (0.5, 1.0, 1.3, 2.0)]
    for hot, rest_max in ((CLIP_TOP_PIXELS - 1, 230), (CLIP_TOP_PIXELS, 200), (CLIP_TOP_PIXELS + 3, 240), (3, 222), (50, 252)):
        image = rng.integers(0, rest_max + 1, (180, 320, 3)).astype(np.uint8)
        flat = image.reshape(-1, 3)
        flat[rng.choice(len(flat), hot, replace=False)] = rng.integers(rest_max, 256, (hot, 3))
        images.append(image)
    return images


def test_frame_clip_levels_match_a_search_per_channel(board_frame):
    color, _ = board_frame
    rng = np.random.default_rng(2)
    for image in _clip_test_images(color, rng):
        expected = []
        for channel in (2, 1, 0):
            counts = np.bincount(image[..., channel].ravel(), minlength=256)
            level = 255 - int(np.searchsorted(np.cumsum(counts[::-1]), CLIP_TOP_PIXELS)) - CLIP_MARGIN
            expected.append(float(min(CLIPPED, level)) if level >= MIN_CLIP_LEVEL else float(CLIPPED))
        np.testing.assert_array_equal(frame_clip_levels_rgb(image), expected)


def test_nearest_centre_is_argmin_of_the_squared_distances():
    rng = np.random.default_rng(4)
    for k in (2, 3, 6):
        pts = rng.normal(size=(3000, 2)).astype(np.float32)
        pts[:10] = pts[10:20]  # duplicates
        centres = rng.normal(size=(k, 2)).astype(np.float32)
        centres[-1] = centres[0]  # a tie: the first wins, as np.argmin
        dx, dy = pts[:, :1] - centres[:, 0], pts[:, 1:] - centres[:, 1]
        np.testing.assert_array_equal(_nearest_centre(pts, centres), np.argmin(dx * dx + dy * dy, axis=1).astype(np.int32))


def test_the_board_plane_fitter_fits_what_fit_board_plane_fits(cfg, board_frame, intrinsics):
    color, depth = board_frame
    cal = calibrate_extrinsics(color, intrinsics, cfg, depth_mm=depth)
    geometry = BlockGeometry(cal, cfg)
    fitter, bp = geometry.fitter, cfg.board_plane
    noisy = depth.astype(np.float64) / 1000.0 + np.random.default_rng(9).normal(0, 0.002, depth.shape)
    noisy[::7, ::5] = 0.0  # holes
    small = noisy[:: 2 * STEP, :: 2 * STEP].astype(np.float32)
    tag_heights = small * fitter.tag_coefficients + fitter.tag_t
    expected = fit_board_plane(small, fitter.x, fitter.y, tag_heights, fitter.on_board, bp.window_m, bp.inlier_m, min_fraction=bp.min_inlier_fraction)
    plane = fitter.fit(small, bp.window_m, bp.inlier_m, min_fraction=bp.min_inlier_fraction)
    np.testing.assert_array_equal(plane.normal, expected.normal)
    assert (plane.distance_m, plane.rms_m, plane.inliers, plane.inlier_fraction) == (
        expected.distance_m, expected.rms_m, expected.inliers, expected.inlier_fraction)


def _robot_mask_before(depth_mm: np.ndarray, cal, volume, step: int) -> np.ndarray:
    """robot_mask as it was written before: every sample in a part's silhouette tested, each part's cells upscaled
    into the mask on their own."""
    rays = _RayGrid(cal, step)
    h, w = cal.height, cal.width
    grid_h, grid_w = rays.x.shape
    mask = np.zeros((h, w), bool)
    local = volume.in_frame(rays.T_camera_world)
    corners_world = volume.hull_corners_m()
    corners_camera = corners_world @ rays.T_camera_world[:3, :3].T + rays.T_camera_world[:3, 3]
    pixels = project_points(cal.T_world_camera, cal.K, cal.dist, corners_world.reshape(-1, 3)).reshape(-1, 8, 2)
    n_capsules = len(local.capsule_radii_m)
    for index, (hull_px, hull_camera) in enumerate(zip(pixels, corners_camera)):
        if not np.all(hull_camera[:, 2] > 0.01):
            continue
        grid_pts = hull_px / step
        x0, y0 = np.maximum(np.floor(grid_pts.min(axis=0)).astype(int), 0)
        x1, y1 = np.minimum(np.ceil(grid_pts.max(axis=0)).astype(int) + 1, (grid_w, grid_h))
        if x0 >= x1 or y0 >= y1:
            continue
        silhouette = np.zeros((y1 - y0, x1 - x0), np.uint8)
        cv2.fillConvexPoly(silhouette, cv2.convexHull(np.round((grid_pts - [x0, y0]) * 16).astype(np.int32)), 1, lineType=cv2.LINE_8, shift=4)
        inside = silhouette.view(bool)
        d_mm = depth_mm[y0 * step : y1 * step : step, x0 * step : x1 * step : step][inside]
        Z = d_mm.astype(np.float32) * np.float32(0.001)
        X, Y = Z * rays.x[y0:y1, x0:x1][inside], Z * rays.y[y0:y1, x0:x1][inside]
        if index < n_capsules:
            (a, b), r = local.capsule_ends_m[index], local.capsule_radii_m[index]
            hit_inside = _in_capsule(X, Y, Z, a, b, r)
        else:
            k = index - n_capsules
            hit_inside = _in_box(X, Y, Z, local.box_poses[k], local.box_half_extents_m[k])
        hit_inside |= d_mm == 0
        hit = np.zeros(inside.shape, bool)
        hit[inside] = hit_inside
        full = mask[y0 * step : y1 * step, x0 * step : x1 * step]
        if step > 1:
            cells = cv2.dilate(hit.view(np.uint8), np.ones((3, 3), np.uint8))
            hit = cv2.resize(cells, (cells.shape[1] * step, cells.shape[0] * step), interpolation=cv2.INTER_NEAREST).view(bool)
        full |= hit[: full.shape[0], : full.shape[1]]
    return mask


@pytest.mark.parametrize("step", [1, 2, 3])
def test_robot_mask_is_every_sample_tested(cfg, board_frame, intrinsics, step):
    """Testing only the samples at a part's depths (the part lies within its box) and upscaling the parts' cells
    once give the mask of testing every sample in every silhouette; depths spread from the camera to past the
    board put points inside, outside and in front of every part, and holes (0 mm) in its silhouette."""
    color, depth = board_frame
    cal = calibrate_extrinsics(color, intrinsics, cfg, depth_mm=depth)
    rng = np.random.default_rng(step)
    noisy = rng.integers(300, 1300, depth.shape).astype(np.uint16)
    noisy[rng.random(depth.shape) > 0.97] = 0
    self_filter = RobotSelfFilter(load_arm("rx200"), cfg.self_filter)
    for joints in ([0.0, 0.0, 0.0, 0.0, 0.0], [0.6, -0.3, 0.4, 0.9, 0.2], [-0.9, 0.5, -0.2, 0.6, -1.0]):
        volume = self_filter.volume(np.array(joints), held_block_edge_m=0.038)
        mask = robot_mask(noisy, cal, volume, step)
        assert 0 < np.count_nonzero(mask) < mask.size
        np.testing.assert_array_equal(mask, _robot_mask_before(noisy, cal, volume, step))


def test_dehomogenise_is_the_broadcast_division():
    from armlab.vision.geometry import dehomogenise

    rng = np.random.default_rng(13)
    for dtype in (np.float64, np.float32):
        points = (rng.normal(size=(1001, 3)) + [0.0, 0.0, 3.0]).astype(dtype)
        expected = points[:, :2] / points[:, 2:3]
        found = dehomogenise(points)
        assert found.dtype == expected.dtype
        np.testing.assert_array_equal(found, expected)


def test_covered_by_stack_counts_in_the_hulls_box_as_over_the_whole_region():
    from armlab.vision.face_shape import covered_by_stack

    rng = np.random.default_rng(14)
    for _ in range(200):
        z = rng.normal(0.04, 0.01, (60, 70))
        z[rng.random(z.shape) > 0.9] = np.nan
        mask = np.zeros(z.shape, np.uint8)
        cv2.ellipse(mask, (int(rng.integers(10, 60)), int(rng.integers(10, 50))), (int(rng.integers(2, 25)), int(rng.integers(2, 20))),
                    float(rng.random() * 180), 0, 360, 1, -1)
        contour = max(cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)[0], key=cv2.contourArea)
        top_m = float(rng.normal(0.035, 0.01))
        inside = np.zeros(z.shape, np.uint8)
        cv2.fillConvexPoly(inside, cv2.convexHull(contour), 1)
        expected = np.count_nonzero((z > top_m + 0.01) & inside.view(bool)) > 0.15 * max(1, np.count_nonzero(inside))
        assert covered_by_stack(contour, top_m, z) == expected


@pytest.mark.parametrize("step", [1, 2, 3])
def test_the_robot_cells_are_the_mask_coarsened(cfg, board_frame, intrinsics, step):
    """detect_blocks reads the self-filter's mask at quarter resolution, and tests regions for robot pixels, on its
    cells (ignore_cells): the same answers as on the mask."""
    from armlab.vision.block_pixels import any_ignored
    from armlab.vision.self_filter import robot_mask_cells

    color, depth = board_frame
    cal = calibrate_extrinsics(color, intrinsics, cfg, depth_mm=depth)
    rng = np.random.default_rng(20 + step)
    noisy = rng.integers(300, 1300, depth.shape).astype(np.uint16)
    volume = RobotSelfFilter(load_arm("rx200"), cfg.self_filter).volume(np.array([0.6, -0.3, 0.4, 0.9, 0.2]), held_block_edge_m=0.038)
    mask, cells = robot_mask_cells(noisy, cal, volume, step)
    assert mask.any()
    if STEP % step == 0:
        np.testing.assert_array_equal(cells[:: STEP // step, :: STEP // step].view(bool), mask[::STEP, ::STEP])
    for _ in range(300):
        x0, y0 = int(rng.integers(0, 1270)), int(rng.integers(0, 710))
        roi = (x0, y0, min(1280, x0 + int(rng.integers(1, 150))), min(720, y0 + int(rng.integers(1, 150))))
        assert any_ignored(mask, (cells, step), roi) == bool(mask[roi[1] : roi[3], roi[0] : roi[2]].any())
