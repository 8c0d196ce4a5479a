"""Objects of any colour from depth alone (seeds/001): fit the table plane by RANSAC, keep the points
above it, cluster them, and report each cluster's centroid, extent and height."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from armlab.errors import InvalidInput
from armlab.vision.calibration import Calibration
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import transform_points


@dataclass(frozen=True)
class DepthObject:
    """A cluster of points above the table: world centroid (m), world axis-aligned extent (m), and its
    height above the plane (95th percentile of the points, robust to depth noise)."""

    centroid_m: np.ndarray
    extent_m: np.ndarray
    height_m: float
    point_count: int
    bbox_px: tuple[int, int, int, int]

    def to_dict(self) -> dict:
        return {
            "centroid_m": self.centroid_m.tolist(),
            "extent_m": self.extent_m.tolist(),
            "height_m": self.height_m,
            "point_count": self.point_count,
            "bbox_px": list(self.bbox_px),
        }


def depth_to_points(depth_mm: np.ndarray, K: np.ndarray, step: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Camera-frame points (H', W', 3) in metres of every step-th pixel (NaN where no reading) and the valid mask."""
    d = depth_mm[::step, ::step].astype(np.float32) / 1000.0
    h, w = d.shape
    us = (np.arange(w, dtype=np.float32) * step - K[0, 2]) / K[0, 0]
    vs = (np.arange(h, dtype=np.float32) * step - K[1, 2]) / K[1, 1]
    valid = d > 0
    pts = np.stack([d * us[None, :], d * vs[:, None], d], axis=-1)
    pts[~valid] = np.nan
    return pts, valid


def fit_plane_ransac(points: np.ndarray, iterations: int, threshold_m: float, seed: int = 0) -> tuple[np.ndarray, float, np.ndarray]:
    """Plane n.x + d = 0 (unit n) with the most inliers, refined by least squares; (n, d, inlier mask).

    ValueError if there are too few points or no plane holds a tenth of them.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 3:
        raise ValueError(f"a plane fit needs (N >= 3, 3) points, got {pts.shape}")
    rng = np.random.default_rng(seed)
    best_count, best = -1, None
    for _ in range(iterations):
        a, b, c = pts[rng.choice(pts.shape[0], 3, replace=False)]
        normal = np.cross(b - a, c - a)
        norm = np.linalg.norm(normal)
        if norm < 1e-9:
            continue
        normal /= norm
        count = int(np.count_nonzero(np.abs(pts @ normal - normal @ a) < threshold_m))
        if count > best_count:
            best_count, best = count, (normal, -normal @ a)
    if best is None or best_count < 0.1 * pts.shape[0]:
        raise InvalidInput("no dominant plane in the depth data")
    normal, d = best
    inliers = np.abs(pts @ normal + d) < threshold_m
    centre = pts[inliers].mean(axis=0)
    _, _, vt = np.linalg.svd(pts[inliers] - centre, full_matrices=False)
    normal = vt[2]
    if normal[2] > 0:  # point the normal toward the camera (camera z looks into the table)
        normal = -normal
    d = -normal @ centre
    return normal, float(d), np.abs(pts @ normal + d) < threshold_m


def detect_objects_from_depth(
    depth_mm: np.ndarray, cal: Calibration, cfg: PerceptionConfig, seed: int = 0, ignore_mask: np.ndarray | None = None
) -> list[DepthObject]:
    """Clusters of points standing above the table plane, whatever their colour, largest first.

    ignore_mask: (H, W) bool pixels that are not the scene (the robot self-filter's mask): never part
    of an object."""
    if not isinstance(depth_mm, np.ndarray) or depth_mm.shape != (cal.height, cal.width):
        raise ValueError(f"depth must be an (H, W) = ({cal.height}, {cal.width}) image in mm")
    if ignore_mask is not None and (not isinstance(ignore_mask, np.ndarray) or ignore_mask.shape != depth_mm.shape or ignore_mask.dtype != bool):
        raise ValueError(f"ignore_mask must be a bool (H, W) = ({cal.height}, {cal.width}) array")
    oc = cfg.objects
    step = 2
    smoothed = cv2.medianBlur(np.ascontiguousarray(depth_mm, dtype=np.uint16), 5)  # depth noise, edges kept
    pts, valid = depth_to_points(smoothed, cal.K, step)
    if np.count_nonzero(valid) < 100:
        raise InvalidInput("the depth image has too few valid readings for a plane fit")
    sample = pts[::4, ::4][valid[::4, ::4]]
    normal, d, _ = fit_plane_ransac(sample, oc.ransac_iterations, oc.ransac_threshold_m, seed)
    with np.errstate(invalid="ignore"):
        height = np.nan_to_num(pts @ normal + d, nan=0.0)
    above = (height > oc.min_height_m).astype(np.uint8)
    if ignore_mask is not None:
        above[ignore_mask[::step, ::step]] = 0
    # Points within cluster_distance join: close gaps of that size in the image before labelling.
    gap_px = max(1, int(round(oc.cluster_distance_m / (np.nanmedian(pts[..., 2]) / cal.K[0, 0] * step))))
    joined = cv2.morphologyEx(above, cv2.MORPH_CLOSE, np.ones((gap_px, gap_px), np.uint8))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(joined, connectivity=8)
    objects = []
    for k in range(1, n):
        sel = (labels == k) & (above > 0)
        if np.count_nonzero(sel) < oc.min_points:
            continue
        world = transform_points(cal.T_world_depth, pts[sel].astype(np.float64))
        x, y, bw, bh = stats[k, :4]
        objects.append(
            DepthObject(
                centroid_m=world.mean(axis=0),
                extent_m=world.max(axis=0) - world.min(axis=0),
                height_m=float(np.percentile(height[sel], 95)),
                point_count=int(np.count_nonzero(sel)),
                bbox_px=(int(x * step), int(y * step), int(bw * step), int(bh * step)),
            )
        )
    return sorted(objects, key=lambda o: -o.point_count)
