"""Pure geometry (rigid fit with the reflection fix) and pixel <-> world on a known camera."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.vision import Calibration, pixel_to_world, world_to_pixel
from armlab.vision.geometry import rigid_transform_3d, transform_points
from synth import L515, look_at_pose


def _rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def test_rigid_fit_recovers_a_known_transform():
    rng = np.random.default_rng(3)
    src = rng.uniform(-0.3, 0.3, (12, 3))
    T = np.eye(4)
    T[:3, :3] = _rotation((0.3, -1.0, 0.4), 2.5)
    T[:3, 3] = (0.1, -0.2, 0.9)
    dst = transform_points(T, src) + rng.normal(0, 1e-4, src.shape)
    fit = rigid_transform_3d(src, dst)
    np.testing.assert_allclose(fit, T, atol=5e-4)


def test_rigid_fit_never_returns_a_reflection():
    """Coplanar points mirrored: plain V U^T gives det = -1; the fix must give a proper rotation."""
    src = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]])
    dst = src * np.array([1, 1, -1]) + np.array([0, 0, 0.01]) * np.arange(4)[:, None]
    fit = rigid_transform_3d(src, dst)
    assert np.linalg.det(fit[:3, :3]) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="at least 3"):
        rigid_transform_3d(src[:2], dst[:2])
    with pytest.raises(ValueError, match="collinear"):
        rigid_transform_3d([[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    with pytest.raises(ValueError, match="NaN"):
        rigid_transform_3d([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], src[:3])


@pytest.fixture(scope="module")
def exact_cal():
    pose = look_at_pose((-0.04, 0.40, 1.0), (0.0, 0.19, 0.0))
    return Calibration(T_world_camera=pose, K=L515.K, dist=np.zeros(5), width=1280, height=720, reprojection_error_px=0.0)


def test_world_to_pixel_and_back_on_the_board_and_at_height(exact_cal):
    pts = np.array([[0.2, 0.3, 0.0], [-0.3, -0.1, 0.0], [0.05, 0.25, 0.038]])
    px = world_to_pixel(exact_cal, pts)
    assert px.shape == (3, 2)
    for (u, v), p in zip(px, pts):
        np.testing.assert_allclose(pixel_to_world(exact_cal, u, v, plane_z_m=p[2]), p, atol=1e-9)
        depth_mm = (exact_cal.T_camera_world @ np.append(p, 1.0))[2] * 1000.0
        np.testing.assert_allclose(pixel_to_world(exact_cal, u, v, depth_mm=depth_mm), p, atol=1e-9)


def test_pixel_to_world_with_a_depth_image(exact_cal):
    p = np.array([0.1, 0.2, 0.0])
    u, v = world_to_pixel(exact_cal, p)[0]
    depth = np.zeros((720, 1280), np.uint16)
    depth_mm = (exact_cal.T_camera_world @ np.append(p, 1.0))[2] * 1000.0
    depth[int(round(v)) - 2 : int(round(v)) + 3, int(round(u)) - 2 : int(round(u)) + 3] = round(depth_mm)
    np.testing.assert_allclose(pixel_to_world(exact_cal, u, v, depth_mm=depth), p, atol=1.5e-3)
    with pytest.raises(ValueError, match="no depth reading"):
        pixel_to_world(exact_cal, 10, 10, depth_mm=depth)


def test_bad_pixels_and_depths_are_refused(exact_cal):
    with pytest.raises(ValueError, match="not finite"):
        pixel_to_world(exact_cal, float("nan"), 3.0)
    with pytest.raises(ValueError, match="outside"):
        pixel_to_world(exact_cal, 1280.0, 3.0)
    with pytest.raises(ValueError, match="positive"):
        pixel_to_world(exact_cal, 640, 360, depth_mm=-5.0)
    with pytest.raises(ValueError, match="behind the camera"):
        pixel_to_world(exact_cal, 640, 360, plane_z_m=2.0)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        world_to_pixel(exact_cal, np.zeros((4, 2)))
