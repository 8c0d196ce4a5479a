"""The pure helpers the perception pass's speed-ups rely on (issue 17, per-frame time): each must give
exactly what it replaces, and its memory must never hand back another input's answer."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.vision import calibrate_extrinsics
from armlab.vision.block_geometry import STEP, BlockGeometry
from armlab.vision.colors import ColorModel, board_region_mask, channel_medians
from armlab.vision.geometry import inverse_homography


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
