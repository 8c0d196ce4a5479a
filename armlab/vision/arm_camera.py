"""The camera's pose from the arm (the Sawyer project's method, seeds/001): the gripper's point seen by
the camera (armlab.vision.gripper_marker) and the same point from forward kinematics, at many poses;
Kabsch (SVD, a reflection turned into the nearest rotation) gives T_base_camera. No board tag needed.

Frames as in DESIGN §3: T_a_b maps b coordinates to a; camera = the depth camera (OpenCV axes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.vision.calibration import CalibrationError
from armlab.vision.geometry import as_points, invert_transform, transform_points

MIN_SPREAD_M = 0.02  # the points' RMS spread across their line: below it the rotation about the line is noise


class ArmCameraError(CalibrationError):
    """The points cannot give the camera's pose (too few, NaN, on a line, or fitting badly); says why."""


@dataclass(frozen=True)
class ArmCameraFit:
    """T_base_camera from n point pairs, each pair's residual (m) after the fit, and the spread (m, RMS
    about the centroid along the points' three principal directions, largest first)."""

    T_base_camera: np.ndarray
    residuals_m: np.ndarray
    spread_m: np.ndarray

    @property
    def residual_mean_m(self) -> float:
        return float(np.mean(self.residuals_m))

    @property
    def residual_max_m(self) -> float:
        return float(np.max(self.residuals_m))


def kabsch(points_src_m, points_dst_m, min_spread_m: float = 0.0) -> np.ndarray:
    """T_dst_src (4x4) minimising sum |T src_i - dst_i|^2: centroids, SVD of the cross-covariance
    H = src_c^T dst_c = U S V^T, R = V diag(1, 1, d) U^T with d = sign det(V U^T), so a reflection
    (noisy or mirrored data) becomes the nearest proper rotation (det +1), never a returned det -1.

    ArmCameraError for fewer than 3 pairs, NaN/inf, sets of different sizes, or points on a line
    (their second principal spread, RMS, below max(min_spread_m, 1e-6 x the first))."""
    try:
        src = as_points(points_src_m, 3, "camera points")
        dst = as_points(points_dst_m, 3, "arm points")
    except ValueError as error:
        raise ArmCameraError(str(error)) from None
    if src.shape != dst.shape:
        raise ArmCameraError(f"{len(src)} camera points but {len(dst)} arm points")
    if len(src) < 3:
        raise ArmCameraError(f"the camera's pose needs at least 3 points, got {len(src)}")
    mu_src, mu_dst = src.mean(axis=0), dst.mean(axis=0)
    src_c, dst_c = src - mu_src, dst - mu_dst
    for name, pts in (("camera", src_c), ("arm", dst_c)):
        spread = principal_spread_m(pts)
        if spread[1] < max(min_spread_m, 1e-6 * spread[0], 1e-12):
            raise ArmCameraError(
                f"the {name} points lie on a line ({spread[1] * 1000:.2f} mm across it, "
                f"{max(min_spread_m, 0.0) * 1000:.0f} mm needed): the rotation about it is not determined"
            )
    u, _, vt = np.linalg.svd(src_c.T @ dst_c)
    d = 1.0 if np.linalg.det(vt.T @ u.T) >= 0.0 else -1.0
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    T = np.eye(4)
    T[:3, :3] = rotation
    T[:3, 3] = mu_dst - rotation @ mu_src
    return T


def principal_spread_m(points_centred: np.ndarray) -> np.ndarray:
    """RMS spread (3,) of centred points along their principal directions, largest first."""
    return np.linalg.svd(points_centred, compute_uv=False) / np.sqrt(len(points_centred))


def fit_camera_from_arm(points_camera_m, points_base_m, min_points: int = 3, min_spread_m: float = MIN_SPREAD_M,
                        max_residual_m: float | None = None) -> ArmCameraFit:
    """Kabsch on the gripper points seen by the camera (camera frame) and given by FK (base frame):
    T_base_camera with each pose's residual. ArmCameraError (the old calibration stays) for fewer than
    min_points pairs, degenerate points (see kabsch), or a mean residual above max_residual_m."""
    n = len(points_camera_m)
    if n < min_points:
        raise ArmCameraError(f"{n} usable poses; the camera's pose from the arm needs at least {min_points}")
    T = kabsch(points_camera_m, points_base_m, min_spread_m)
    cam = as_points(points_camera_m, 3)
    base = as_points(points_base_m, 3)
    residuals = np.linalg.norm(transform_points(T, cam) - base, axis=1)
    fit = ArmCameraFit(T_base_camera=T, residuals_m=residuals, spread_m=principal_spread_m(base - base.mean(axis=0)))
    if max_residual_m is not None and fit.residual_mean_m > max_residual_m:
        raise ArmCameraError(
            f"the fit leaves {fit.residual_mean_m * 1000:.1f} mm mean residual (limit {max_residual_m * 1000:.0f} mm, "
            f"worst {fit.residual_max_m * 1000:.1f} mm): the camera saw something else, or the arm is not where FK says"
        )
    return fit


def pose_difference(T_a, T_b) -> tuple[float, float]:
    """Position (m) and rotation (deg) between two poses of one thing in one frame."""
    A, B = np.asarray(T_a, float), np.asarray(T_b, float)
    delta = invert_transform(A) @ B
    cos = (np.trace(delta[:3, :3]) - 1.0) / 2.0
    return float(np.linalg.norm(A[:3, 3] - B[:3, 3])), float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
