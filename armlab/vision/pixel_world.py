"""Pixel <-> world through a calibration: with depth (back-projection) or without (ray meets a
horizontal plane), and world -> pixel for drawing."""

from __future__ import annotations

import math

import numpy as np

from armlab.vision.calibration import Calibration, depth_at
from armlab.vision.geometry import backproject, intersect_rays_with_plane, normalized_rays, project_points, transform_points


def pixel_to_world(
    cal: Calibration, u: float, v: float, depth_mm: np.ndarray | float | None = None, plane_z_m: float = 0.0
) -> np.ndarray:
    """World point (3,) seen at pixel (u, v).

    depth_mm: a depth image (H, W) in mm (median of the valid readings around the pixel), or one
    reading in mm; None intersects the viewing ray with the plane z = plane_z_m instead.
    ValueError for a non-finite or out-of-image pixel, or no valid depth reading there.
    """
    if not (math.isfinite(u) and math.isfinite(v)):
        raise ValueError(f"pixel ({u}, {v}) is not finite")
    if not (-0.5 <= u < cal.width - 0.5 and -0.5 <= v < cal.height - 0.5):
        raise ValueError(f"pixel ({u:.1f}, {v:.1f}) is outside the {cal.width}x{cal.height} image")
    pixel = np.array([[u, v]], dtype=np.float64)
    if depth_mm is None:
        if not math.isfinite(plane_z_m):
            raise ValueError("plane_z_m must be finite")
        rays = normalized_rays(pixel, cal.K, cal.dist)
        return intersect_rays_with_plane(cal.T_world_camera, rays, plane_z_m)[0]
    if isinstance(depth_mm, np.ndarray) and depth_mm.ndim == 2:
        if depth_mm.shape != (cal.height, cal.width):
            raise ValueError(f"depth image is {depth_mm.shape[::-1]} but the calibration is for {cal.width}x{cal.height}")
        depth = depth_at(depth_mm, u, v, radius=1)
        if depth <= 0:
            raise ValueError(f"no depth reading at pixel ({u:.0f}, {v:.0f})")
    else:
        depth = float(depth_mm)
        if not math.isfinite(depth) or depth <= 0:
            raise ValueError(f"depth must be a positive number of mm, got {depth_mm}")
    camera_point = backproject(pixel, np.array([depth / 1000.0]), cal.K, cal.dist)
    return transform_points(cal.T_world_camera, camera_point)[0]


def world_to_pixel(cal: Calibration, points_m: np.ndarray) -> np.ndarray:
    """Pixels (N, 2) of world points (N, 3) (a single (3,) point gives (1, 2))."""
    return project_points(cal.T_world_camera, cal.K, cal.dist, points_m)
