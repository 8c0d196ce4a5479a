"""depth_point_cloud (the 3-D panel's depth points): a camera looking straight down from 1 m at a flat board
with a 38 mm block gives points on z = 0 and on the block's top at 38 mm, every step-th pixel, coloured by
the colour image at the same pixel (BGR -> RGB), pixels without a reading left out."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.errors import InvalidInput
from armlab.vision.calibration import Calibration
from armlab.vision.pixel_world import depth_point_cloud

W, H = 160, 120


def _down_looking() -> Calibration:
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # camera z down, image y toward world -y
    T[:3, 3] = [0.0, 0.0, 1.0]
    K = np.array([[100.0, 0.0, W / 2], [0.0, 100.0, H / 2], [0.0, 0.0, 1.0]])
    return Calibration(T_world_camera=T, K=K, dist=np.zeros(5), width=W, height=H, reprojection_error_px=0.1)


def test_board_and_block_top_land_at_their_heights_in_their_colours():
    depth = np.full((H, W), 1000.0)
    depth[40:60, 60:90] = 962.0  # a block top 38 mm above the board
    depth[0:8, :] = 0.0  # no reading
    color = np.zeros((H, W, 3), np.uint8)
    color[..., 0] = 200  # blue in BGR
    color[40:60, 60:90] = (0, 0, 255)  # red block
    points, colors = depth_point_cloud(_down_looking(), depth, color, step_px=4)
    assert points.dtype == np.float32 and colors.dtype == np.uint8 and len(points) == len(colors)
    assert len(points) == (H // 4 - 2) * (W // 4)  # every 4th pixel, the rows without a reading left out
    top = colors[:, 0] == 255  # rows 42..58 and columns 62..86 of the sampled pixels (2, 6, 10, ...)
    assert top.sum() == 5 * 7 and np.allclose(points[top, 2], 0.038, atol=1e-6)
    assert np.allclose(points[~top, 2], 0.0, atol=1e-6)
    assert np.all(colors[~top] == (0, 0, 200))  # RGB
    centre = points[top].mean(axis=0)
    assert centre[0] == pytest.approx((74 - W / 2) / 100 * 0.962, abs=0.01)


def test_a_depth_image_of_another_size_or_a_zero_step_is_refused():
    with pytest.raises(InvalidInput):
        depth_point_cloud(_down_looking(), np.ones((H // 2, W // 2)), np.zeros((H, W, 3), np.uint8), 4)
    with pytest.raises(InvalidInput):
        depth_point_cloud(_down_looking(), np.ones((H, W)), np.zeros((H, W, 3), np.uint8), 0)
