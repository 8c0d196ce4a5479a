"""The guided checkerboard capture's pure checks (armlab.vision.intrinsics_capture) on synthetic views:
a printed board warped into a pinhole camera of known K. Board not found, too blurry (blurred here on
purpose), duplicate, too few views and too high an error are refused with their reason; K is recovered."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from armlab.devices.sim.checkerboard import CheckerboardTarget, calibration_poses, checkerboard_texture
from armlab.vision.intrinsics_capture import IntrinsicsCapture, IntrinsicsRejected, load_intrinsics_config

K_TRUE = np.array([[880.0, 0.0, 630.0], [0.0, 880.0, 370.0], [0.0, 0.0, 1.0]])
SIZE = (1280, 720)


@pytest.fixture(scope="module")
def config():
    return load_intrinsics_config()


def synthetic_view(config, position_m, rotvec_rad, px_per_square: int = 48) -> np.ndarray:
    """A grey image of the configured board at a pose in the camera frame (turned from facing the camera)."""
    t = config.target
    target = CheckerboardTarget(t.pattern, t.square_m, t.margin_squares)
    texture = cv2.cvtColor(checkerboard_texture(target, px_per_square), cv2.COLOR_RGB2GRAY)
    h, w = texture.shape
    half_w, half_h = (0.5 * s for s in target.size_m)
    # Texture corners in the board frame: row 0 is +y (top), column 0 is -x; the board faces the camera (z toward it).
    board = np.array([[-half_w, half_h, 0], [half_w, half_h, 0], [half_w, -half_h, 0], [-half_w, -half_h, 0]])
    R = cv2.Rodrigues(np.asarray(rotvec_rad, float))[0] @ np.diag([1.0, -1.0, -1.0])
    image_px, _ = cv2.projectPoints(board, cv2.Rodrigues(R)[0], np.asarray(position_m, float), K_TRUE, None)
    H = cv2.getPerspectiveTransform(np.float32([[0, 0], [w, 0], [w, h], [0, h]]), image_px.reshape(4, 2).astype(np.float32))
    background = np.full((SIZE[1], SIZE[0]), 110, np.uint8)
    warped = cv2.warpPerspective(texture, H, SIZE, flags=cv2.INTER_AREA)
    mask = cv2.warpPerspective(np.full_like(texture, 255), H, SIZE)
    return np.where(mask > 127, warped, background)


def test_k_recovered_from_synthetic_views(config):
    capture = IntrinsicsCapture(config, SIZE)
    for position_m, rotvec in calibration_poses(12, seed=1, focal_px=880.0):
        capture.add(synthetic_view(config, position_m, rotvec))
    result = capture.solve()
    assert abs(result.K[0, 0] - 880.0) < 3.0 and abs(result.K[1, 1] - 880.0) < 3.0
    assert abs(result.K[0, 2] - 630.0) < 2.0 and abs(result.K[1, 2] - 370.0) < 2.0
    assert len(result.per_view_errors) == 12 and max(result.per_view_errors) < 0.3
    coverage = capture.to_dict()
    assert coverage["coverage_fraction"] > 0.4 and len(coverage["coverage"]) == config.capture.coverage_grid[1]


def test_no_board_is_refused_and_nothing_kept(config):
    capture = IntrinsicsCapture(config, SIZE)
    with pytest.raises(IntrinsicsRejected, match="checkerboard not found") as caught:
        capture.add(np.full((SIZE[1], SIZE[0]), 120, np.uint8))
    assert caught.value.code == "not_found" and capture.views == []
    half = synthetic_view(config, (0.0, 0.0, 0.6), (0.2, 0.1, 0.0))
    half[:, 640:] = 110  # half the board hidden
    with pytest.raises(IntrinsicsRejected, match="checkerboard not found"):
        capture.add(half)


def test_blurry_view_is_refused(config):
    sharp = synthetic_view(config, (0.0, 0.0, 0.6), (0.3, -0.2, 0.1))
    blurred = cv2.GaussianBlur(sharp, (0, 0), 3.0)
    capture = IntrinsicsCapture(config, SIZE)
    with pytest.raises(IntrinsicsRejected, match="too blurry") as caught:
        capture.add(blurred)
    assert caught.value.code == "blurry" and capture.views == []
    assert capture.add(sharp).edge_width_px < config.capture.max_edge_width_px  # the same view, sharp, is kept


def test_duplicate_view_is_refused_a_moved_one_kept(config):
    capture = IntrinsicsCapture(config, SIZE)
    capture.add(synthetic_view(config, (0.0, 0.0, 0.6), (0.3, 0.0, 0.0)))
    with pytest.raises(IntrinsicsRejected, match="duplicate of view 0") as caught:
        capture.add(synthetic_view(config, (0.004, 0.0, 0.6), (0.3, 0.0, 0.0)))  # ~6 px away
    assert caught.value.code == "duplicate" and len(capture.views) == 1
    capture.add(synthetic_view(config, (0.05, 0.0, 0.6), (0.3, 0.0, 0.0)))  # ~70 px away: a new view
    assert len(capture.views) == 2


def test_too_few_views_and_too_high_error_are_refused(config):
    capture = IntrinsicsCapture(config, SIZE)
    poses = calibration_poses(10, seed=2, focal_px=880.0)
    for position_m, rotvec in poses[:9]:
        capture.add(synthetic_view(config, position_m, rotvec))
    with pytest.raises(IntrinsicsRejected, match="too few views: 9 kept, 10 needed"):
        capture.solve()
    capture.add(synthetic_view(config, *poses[9]))
    rng = np.random.default_rng(0)
    capture.views[4].corners_px = capture.views[4].corners_px + rng.normal(0, 6.0, capture.views[4].corners_px.shape).astype(np.float32)
    with pytest.raises(IntrinsicsRejected, match=r"error too high: RMS .* view 4 is worst") as caught:
        capture.solve()
    assert caught.value.code == "error_too_high"
    capture.delete(4)
    capture.add(synthetic_view(config, (0.02, 0.01, 0.62), (-0.3, 0.2, 0.0)))
    assert capture.solve().rms < config.capture.max_rms_px
