"""Pixel <-> world through a calibration: with depth (back-projection) or without (ray meets a
horizontal plane), depth that is not the robot's (pixel_to_world_off_robot), and world -> pixel for drawing."""

from __future__ import annotations

import math

import numpy as np

from armlab.errors import InvalidInput
from armlab.vision.calibration import Calibration, depth_at
from armlab.vision.geometry import (
    as_points,
    backproject,
    intersect_rays_with_plane,
    invert_transform,
    normalized_rays,
    project_points,
    transform_points,
)


def pixel_to_world(
    cal: Calibration, u: float, v: float, depth_mm: np.ndarray | float | None = None, plane_z_m: float = 0.0
) -> np.ndarray:
    """World point (3,) seen at pixel (u, v).

    depth_mm: a depth image (H, W) in mm (median of the valid readings around the pixel), or one
    reading in mm; None intersects the viewing ray with the plane z = plane_z_m instead.
    ValueError for a non-finite or out-of-image pixel, or no valid depth reading there.
    """
    if not (math.isfinite(u) and math.isfinite(v)):
        raise InvalidInput(f"pixel ({u}, {v}) is not finite")
    if not (-0.5 <= u < cal.width - 0.5 and -0.5 <= v < cal.height - 0.5):
        raise InvalidInput(f"pixel ({u:.1f}, {v:.1f}) is outside the {cal.width}x{cal.height} image")
    pixel = np.array([[u, v]], dtype=np.float64)
    if depth_mm is None:
        if not math.isfinite(plane_z_m):
            raise InvalidInput("plane_z_m must be finite")
        rays = normalized_rays(pixel, cal.K, cal.dist)
        return intersect_rays_with_plane(cal.T_world_camera, rays, plane_z_m)[0]
    if isinstance(depth_mm, np.ndarray) and depth_mm.ndim == 2:
        if depth_mm.shape != (cal.height, cal.width):
            raise InvalidInput(f"depth image is {depth_mm.shape[::-1]} but the calibration is for {cal.width}x{cal.height}")
        depth = depth_at(depth_mm, u, v, radius=1)
        if depth <= 0:
            raise InvalidInput(f"no depth reading at pixel ({u:.0f}, {v:.0f})")
    else:
        depth = float(depth_mm)
        if not math.isfinite(depth) or depth <= 0:
            raise InvalidInput(f"depth must be a positive number of mm, got {depth_mm}")
    camera_point = backproject(pixel, np.array([depth / 1000.0]), cal.K, cal.dist)
    return transform_points(cal.T_world_depth, camera_point)[0]  # the depth camera's board lands at z = 0


def pixel_to_world_off_robot(
    cal: Calibration, u: float, v: float, depth_mm: np.ndarray | None, robot=None, remembered_depth_mm: np.ndarray | None = None,
    radius: int = 1,
) -> tuple[np.ndarray, str]:
    """(world point (3,), source) at pixel (u, v), never from a depth reading of the robot.

    robot: the robot's inflated volume at the frame's joints (armlab.vision.self_filter.RobotVolume, or
    anything with contains(points (N, 3)) -> (N,) bool), None when unknown. The depth readings of the
    (2r+1)² window whose points lie outside it give the median depth ("depth"); when every one is the
    robot (or missing), remembered_depth_mm, depth (H, W) mm seen there while the robot did not cover
    the pixel (0 = never seen), gives it ("remembered"); else the viewing ray meets the board plane
    z = 0 ("board"). ValueError for a non-finite or out-of-image pixel.
    """
    board = pixel_to_world(cal, u, v)  # validates the pixel
    for source, depth in (("depth", depth_mm), ("remembered", remembered_depth_mm)):
        if depth is None:
            continue
        if depth.shape != (cal.height, cal.width):
            raise InvalidInput(f"depth image is {depth.shape[::-1]} but the calibration is for {cal.width}x{cal.height}")
        ui, vi = int(round(u)), int(round(v))
        rows, cols = np.mgrid[max(0, vi - radius) : vi + radius + 1, max(0, ui - radius) : ui + radius + 1]
        rows, cols = rows.ravel(), cols.ravel()
        inside = (rows < cal.height) & (cols < cal.width)
        rows, cols = rows[inside], cols[inside]
        readings_m = depth[rows, cols].astype(np.float64) / 1000.0
        valid = readings_m > 0
        if not valid.any():
            continue
        pixels = np.column_stack([cols[valid], rows[valid]]).astype(np.float64)
        T_world_depth = cal.T_world_depth
        points = transform_points(T_world_depth, backproject(pixels, readings_m[valid], cal.K, cal.dist))
        keep = ~robot.contains(points) if (robot is not None and source == "depth") else np.ones(len(points), bool)
        if keep.any():
            median_m = float(np.median(readings_m[valid][keep]))
            camera_point = backproject(np.array([[u, v]], dtype=np.float64), np.array([median_m]), cal.K, cal.dist)
            return transform_points(T_world_depth, camera_point)[0], source
    return board, "board"


def depth_points_to_world(cal: Calibration, points_camera_m: np.ndarray) -> np.ndarray:
    """World points (N, 3) of aligned-depth points (N, 3) (back-projected with K, dist), each kept on its colour
    pixel's ray (T_world_camera: the tags' pose) at the height the depth gives less the depth board's height at the
    point's own (x, y) (the plane calibration measured: offset and tilt, see board_plane).

    Why: aligned depth is wrong along each pixel's ray only, so the rigid T_world_depth that puts the board at
    z = 0 moves points above it sideways by their height times the tilt and by the offset times the ray's slant:
    the gripper tag 150-220 mm up came out 1-5 mm off on the realistic camera. Without a depth correction this is
    T_world_camera's mapping."""
    X = as_points(points_camera_m, 3, "points_camera_m")
    T_wc, T_wd = np.asarray(cal.T_world_camera, float), np.asarray(cal.T_world_depth, float)
    seen = transform_points(T_wc, X)  # on the right rays, at the ranges the depth gives
    plane = T_wd[2] @ invert_transform(T_wc)  # the depth's board, world: plane . (x, y, z, 1) = 0
    centre = T_wc[:3, 3]
    ray = seen - centre
    points = seen
    for _ in range(3):  # the board's height under the point moves as the point does (a few mm over a tilt of ~1.5 deg)
        board_z = -(plane[0] * points[:, 0] + plane[1] * points[:, 1] + plane[3]) / plane[2]
        scale = (seen[:, 2] - board_z - centre[2]) / ray[:, 2]
        points = centre + ray * scale[:, None]
    return points


def world_to_pixel(cal: Calibration, points_m: np.ndarray) -> np.ndarray:
    """Pixels (N, 2) of world points (N, 3) (a single (3,) point gives (1, 2))."""
    return project_points(cal.T_world_camera, cal.K, cal.dist, points_m)


def depth_point_cloud(cal: Calibration, depth_mm: np.ndarray, color_bgr: np.ndarray, step_px: int) -> tuple[np.ndarray, np.ndarray]:
    """The depth image as world points, every step_px-th pixel in u and v with a valid reading: (points (N, 3)
    metres, float32; colours (N, 3) RGB uint8 from the colour image at the same pixels). The depth image must be
    the calibration's size (the colour image is sampled at the same pixels, scaled if its size differs)."""
    if step_px < 1:
        raise InvalidInput(f"step_px must be at least 1, got {step_px}")
    if depth_mm.shape != (cal.height, cal.width):
        raise InvalidInput(f"depth image is {depth_mm.shape[::-1]} but the calibration is for {cal.width}x{cal.height}")
    v, u = np.mgrid[step_px // 2:cal.height:step_px, step_px // 2:cal.width:step_px]
    depth = depth_mm[v, u].astype(np.float64)
    valid = np.isfinite(depth) & (depth > 0)
    u, v, depth = u[valid], v[valid], depth[valid]
    pixels = np.column_stack([u, v]).astype(np.float64)
    points = transform_points(cal.T_world_depth, backproject(pixels, depth / 1000.0, cal.K, cal.dist))
    cu = np.clip((u * color_bgr.shape[1]) // cal.width, 0, color_bgr.shape[1] - 1)
    cv = np.clip((v * color_bgr.shape[0]) // cal.height, 0, color_bgr.shape[0] - 1)
    colors = color_bgr[cv, cu][:, ::-1]
    return points.astype(np.float32), np.ascontiguousarray(colors, dtype=np.uint8)
