"""Calibration without tags: the operator clicks >= 4 image points whose world coordinates are known
(board grid corners, or typed). The board homography is fitted from them and, with the intrinsics,
the camera pose (PnP); with depth, cross-checked by a rigid fit of the back-projected clicks.
Bad input (too few, collinear, repeated, off-image or off-board points) is a CalibrationError saying why."""

from __future__ import annotations

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.vision.calibration import Calibration, CalibrationError, depth_at
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import backproject, invert_transform, project_points, rigid_transform_3d, transform_points

MIN_POINTS = 4
MIN_SPREAD_M = 0.02  # the world points must span at least this much in both directions of the board plane
MIN_SPREAD_PX = 10.0


def _checked_points(pixels_px, world_m, intrinsics: Intrinsics) -> tuple[np.ndarray, np.ndarray]:
    pixels = np.asarray(pixels_px, dtype=np.float64)
    world = np.asarray(world_m, dtype=np.float64)
    if pixels.ndim != 2 or pixels.shape[1] != 2:
        raise CalibrationError(f"pixels must be a list of (u, v), got shape {pixels.shape}")
    if world.ndim != 2 or world.shape[1] not in (2, 3):
        raise CalibrationError(f"world points must be a list of (x, y) or (x, y, z) in metres, got shape {world.shape}")
    if len(pixels) != len(world):
        raise CalibrationError(f"{len(pixels)} pixels but {len(world)} world points: give one world point per click")
    if len(pixels) < MIN_POINTS:
        raise CalibrationError(f"click calibration needs at least {MIN_POINTS} points, got {len(pixels)}")
    if world.shape[1] == 2:
        world = np.hstack([world, np.zeros((len(world), 1))])
    if not (np.all(np.isfinite(pixels)) and np.all(np.isfinite(world))):
        raise CalibrationError("a clicked pixel or world point is not a finite number")
    outside = [i for i, (u, v) in enumerate(pixels) if not (0 <= u < intrinsics.width and 0 <= v < intrinsics.height)]
    if outside:
        raise CalibrationError(f"points {outside} are outside the {intrinsics.width}x{intrinsics.height} image")
    for name, pts, least in (("world", world[:, :2], MIN_SPREAD_M), ("image", pixels, MIN_SPREAD_PX)):
        spread = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False) / np.sqrt(len(pts))
        if spread[-1] < least:
            raise CalibrationError(
                f"the {name} points are (nearly) collinear or repeated (spread {spread[-1]:.3g} across their line): "
                "click points spread over the board, not along one line")
    return pixels, world


def _check_on_board(world: np.ndarray, cfg: PerceptionConfig) -> None:
    """CalibrationError naming the world points whose x, y lie off the board (a typo, or the wrong corner)."""
    (x0, x1), (y0, y1) = cfg.board.x_range_m, cfg.board.y_range_m
    tol = 1e-3
    off = [i for i, (x, y, _) in enumerate(world) if not (x0 - tol <= x <= x1 + tol and y0 - tol <= y <= y1 + tol)]
    if off:
        shown = ", ".join(f"{i} at ({world[i, 0] * 1000:.0f}, {world[i, 1] * 1000:.0f}) mm" for i in off)
        raise CalibrationError(f"point{'s' if len(off) > 1 else ''} {shown} off the board (x {x0 * 1000:.0f} to "
                               f"{x1 * 1000:.0f} mm, y {y0 * 1000:.0f} to {y1 * 1000:.0f} mm): check the world coordinates")


def calibrate_from_points(
    pixels_px, world_m, intrinsics: Intrinsics, cfg: PerceptionConfig, depth_mm: np.ndarray | None = None,
) -> tuple[Calibration, dict]:
    """A Calibration from clicked pixels (N, 2) and their world points (N, 2 at z = 0, or N, 3), N >= 4,
    and a report: homography (board xy -> undistorted pixels) with its RMS error, PnP reprojection
    error, per-point errors (px). CalibrationError when the points cannot give a trustworthy pose."""
    pixels, world = _checked_points(pixels_px, world_m, intrinsics)
    _check_on_board(world, cfg)
    K = intrinsics.K
    dist = np.asarray(intrinsics.dist, dtype=np.float64)
    undistorted = cv2.undistortPoints(pixels.reshape(-1, 1, 2), K, dist, P=K).reshape(-1, 2)
    report: dict = {"points": len(pixels)}
    planar = bool(np.allclose(world[:, 2], 0.0))
    if planar:
        H, _ = cv2.findHomography(world[:, :2], undistorted, 0)
        if H is None:
            raise CalibrationError("no homography fits the clicked points")
        mapped = cv2.perspectiveTransform(world[:, :2].reshape(-1, 1, 2), H).reshape(-1, 2)
        report["H_image_board"] = (H / H[2, 2]).tolist()
        report["homography_error_px"] = float(np.sqrt(np.mean(np.sum((mapped - undistorted) ** 2, axis=1))))
    flags = cv2.SOLVEPNP_IPPE if planar else cv2.SOLVEPNP_SQPNP
    ok, rvec, tvec = cv2.solvePnP(world, pixels, K, dist, flags=flags)
    if not ok:
        raise CalibrationError("PnP found no camera pose for the clicked points")
    rvec, tvec = cv2.solvePnPRefineLM(world, pixels, K, dist, rvec, tvec)
    T_camera_world = np.eye(4)
    T_camera_world[:3, :3] = cv2.Rodrigues(rvec)[0]
    T_camera_world[:3, 3] = tvec.ravel()
    T_world_camera = invert_transform(T_camera_world)
    errors = np.linalg.norm(project_points(T_world_camera, K, dist, world) - pixels, axis=1)
    rms = float(np.sqrt(np.mean(errors**2)))
    report["reprojection_error_px"] = rms
    report["point_errors_px"] = errors.round(3).tolist()
    limit = cfg.calibration.max_reprojection_error_px
    if rms > limit:
        worst = int(np.argmax(errors))
        raise CalibrationError(f"clicked points reproject with {rms:.2f} px RMS (limit {limit} px); point {worst} is off by "
                               f"{errors[worst]:.1f} px: a click or its world point is wrong")
    if T_world_camera[2, 3] <= 0:
        raise CalibrationError("the solved camera is below the board: the world points do not match the clicks")
    T_depth, depth_error = None, None
    if depth_mm is not None:
        depths_m = np.array([depth_at(depth_mm, u, v) for u, v in pixels]) / 1000.0
        valid = depths_m > 0
        if valid.sum() >= 3:
            # A click on a spot something stands on (a block, the arm's base) measures that, not the board:
            # such points are left out of the cross-check; the pose must agree with the depth of the rest.
            camera_pts = backproject(pixels[valid], depths_m[valid], K, dist)
            residual_m = np.linalg.norm(transform_points(T_world_camera, camera_pts) - world[valid], axis=1)
            limit_m = cfg.calibration.max_depth_check_error_m
            agree = residual_m <= limit_m
            report["depth_points_ignored"] = int(len(residual_m) - agree.sum())
            if agree.sum() < 3:
                raise CalibrationError(f"depth cross-check disagrees with the clicked pose: only {int(agree.sum())} of "
                                       f"{len(residual_m)} points are within {limit_m * 1000:.0f} mm of their depth")
            T_depth = rigid_transform_3d(camera_pts[agree], world[valid][agree])
            depth_error = float(np.sqrt(np.mean(residual_m[agree] ** 2)))
    report["depth_check_error_m"] = depth_error
    calibration = Calibration(T_world_camera=T_world_camera, K=K, dist=dist, width=intrinsics.width, height=intrinsics.height,
                              reprojection_error_px=rms, depth_check_error_m=depth_error, T_world_camera_depth=T_depth)
    return calibration, report
