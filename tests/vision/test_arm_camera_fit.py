"""Kabsch for the camera's pose from the arm (armlab.vision.arm_camera): a known transform recovered
through noise, a mirrored point set answered by a proper rotation, degenerate input refused saying why."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.vision.arm_camera import ArmCameraError, fit_camera_from_arm, kabsch, pose_difference


def random_rotation(rng) -> np.ndarray:
    """A uniformly random rotation (QR of a Gaussian matrix, signs fixed, det +1)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    return q if np.linalg.det(q) > 0 else -q


def gripper_points(rng, n: int = 15) -> np.ndarray:
    """Points like the calibration's: spread over 0.4 x 0.25 x 0.16 m in front of the arm."""
    return rng.uniform([-0.2, 0.15, 0.08], [0.2, 0.40, 0.24], (n, 3))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kabsch_recovers_a_random_transform_through_noise(seed):
    rng = np.random.default_rng(seed)
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng)
    T[:3, 3] = rng.uniform([-0.1, 0.3, 0.9], [0.1, 0.45, 1.1])  # where the overhead camera hangs
    base = gripper_points(rng)
    camera = (base - T[:3, 3]) @ T[:3, :3] + rng.normal(0.0, 0.0003, base.shape)  # camera = T^-1 base, 0.3 mm noise
    fit = fit_camera_from_arm(camera, base)
    position_m, angle_deg = pose_difference(fit.T_base_camera, T)
    assert position_m < 0.003 and angle_deg < 0.2  # ~1 mrad of rotation from the noise, over a lever of ~1 m
    assert np.linalg.det(fit.T_base_camera[:3, :3]) == pytest.approx(1.0)
    assert len(fit.residuals_m) == 15 and fit.residual_max_m < 0.003  # each pose's residual: the noise, not more


def test_a_mirrored_point_set_gives_a_proper_rotation_not_a_reflection():
    """The arm's points mirrored in a plane: V U^T alone is a reflection (det -1, checked here); the fit
    turns it into the nearest rotation (det +1) instead of returning it."""
    rng = np.random.default_rng(5)
    base = gripper_points(rng)
    camera = base * np.array([1.0, 1.0, -1.0])
    src_c, dst_c = camera - camera.mean(axis=0), base - base.mean(axis=0)
    u, _, vt = np.linalg.svd(src_c.T @ dst_c)
    assert np.linalg.det(vt.T @ u.T) == pytest.approx(-1.0)  # the case the check exists for
    T = kabsch(camera, base)
    assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-9)


def test_degenerate_input_is_refused_with_the_reason():
    rng = np.random.default_rng(7)
    base = gripper_points(rng)
    on_a_line = np.outer(np.linspace(0.0, 0.3, 12), [1.0, 0.5, 0.2]) + rng.normal(0.0, 0.0002, (12, 3))
    with pytest.raises(ArmCameraError, match="on a line"):
        fit_camera_from_arm(on_a_line, on_a_line + 0.1)
    with pytest.raises(ArmCameraError, match="at least 3"):
        kabsch(base[:2], base[:2])
    with pytest.raises(ArmCameraError, match="NaN"):
        kabsch(np.vstack([base[:-1], [np.nan, 0.0, 0.0]]), base)
    with pytest.raises(ArmCameraError, match="14 camera points but 15 arm points"):
        kabsch(base[:-1], base)
    with pytest.raises(ArmCameraError, match="11 usable poses.*at least 12"):
        fit_camera_from_arm(base[:11], base[:11], min_points=12)


def test_a_fit_that_leaves_a_large_residual_is_refused():
    rng = np.random.default_rng(9)
    base = gripper_points(rng)
    camera = base + rng.normal(0.0, 0.02, base.shape)  # the camera saw something 20 mm off, at random
    with pytest.raises(ArmCameraError, match="mean residual"):
        fit_camera_from_arm(camera, base, max_residual_m=0.01)
