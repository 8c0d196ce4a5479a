"""Find the gripper in the camera by the tag fixed on it (the workcell's `gripper.marker`): its centre
in colour (the tag's diagonals crossing: exact under perspective), its range from the aligned depth
(a plane fitted to the depth points inside the tag, met by the centre's ray), giving a 3-D point in
the depth camera's frame (OpenCV axes, metres). Works the same on a real RX200 with a printed tag.

The point is where the depth camera sees the tag: on a real RGB-D camera whose depth sits a few mm
off the colour camera's (calibration.depth_correction), a pose fitted to such points is the depth
camera's (compare it with Calibration.T_world_depth).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.vision.geometry import backproject, normalized_rays
from armlab.vision.tags import Tag

INNER_FRACTION = 0.7  # depth is read inside the tag's square shrunk to this fraction (clear of its edges)
MIN_DEPTH_POINTS = 12  # fewer valid depth readings on the tag than this: no range
MAX_PLANE_RMS_M = 0.004  # the tag is flat: depth points further than this from a plane are not the tag


class MarkerNotFound(ValueError):
    """The gripper's tag is not in this frame, or the depth has no usable range on it; says which."""


@dataclass(frozen=True)
class MarkerSighting:
    """The gripper tag seen in one frame: its centre pixel (u, v), the 3-D centre in the depth camera's
    frame (metres), the number of depth readings used and their RMS distance from the fitted plane (m)."""

    pixel: np.ndarray
    point_camera_m: np.ndarray
    depth_points: int
    plane_rms_m: float


def tag_centre_px(corners_px: np.ndarray) -> np.ndarray:
    """Where the quad's diagonals cross (the square's projected centre; the mean of the corners is not)."""
    c = np.asarray(corners_px, dtype=np.float64).reshape(4, 2)
    p, r = c[0], c[2] - c[0]
    q, s = c[1], c[3] - c[1]
    denom = r[0] * s[1] - r[1] * s[0]
    if abs(denom) < 1e-9:
        return c.mean(axis=0)
    t = ((q[0] - p[0]) * s[1] - (q[1] - p[1]) * s[0]) / denom
    return p + t * r


def _inside_quad(corners_px: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the pixels inside the quad shrunk about its centre to INNER_FRACTION."""
    centre = tag_centre_px(corners_px)
    quad = centre + INNER_FRACTION * (np.asarray(corners_px, float) - centre)
    u0, v0 = np.floor(quad.min(axis=0)).astype(int)
    u1, v1 = np.ceil(quad.max(axis=0)).astype(int)
    u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, shape[1] - 1), min(v1, shape[0] - 1)
    if u1 < u0 or v1 < v0:
        return np.empty(0, int), np.empty(0, int)
    vs, us = np.mgrid[v0 : v1 + 1, u0 : u1 + 1]
    us, vs = us.ravel(), vs.ravel()
    inside = np.ones(us.shape, bool)
    for k in range(4):  # same side of every edge as the centre
        a, b = quad[k], quad[(k + 1) % 4]
        side = (b[0] - a[0]) * (vs - a[1]) - (b[1] - a[1]) * (us - a[0])
        centre_side = (b[0] - a[0]) * (centre[1] - a[1]) - (b[1] - a[1]) * (centre[0] - a[0])
        inside &= side * np.sign(centre_side) >= 0
    return vs[inside], us[inside]


def locate_marker(tag: Tag, depth_mm: np.ndarray, K: np.ndarray, dist: np.ndarray) -> MarkerSighting:
    """The tag's centre in the depth camera's frame from its corners and the aligned depth image
    ((H, W) integer mm, 0 = none). MarkerNotFound when too few depth readings fall on the tag or they
    do not lie on a plane (the tag is partly hidden by something nearer)."""
    depth = np.asarray(depth_mm)
    if depth.ndim != 2 or depth.dtype.kind not in "ui":
        raise MarkerNotFound(f"depth must be an integer (H, W) image in mm, got {depth.shape} {depth.dtype}")
    rows, cols = _inside_quad(tag.corners_px, depth.shape)
    d_m = depth[rows, cols].astype(np.float64) / 1000.0
    valid = d_m > 0
    if int(valid.sum()) < MIN_DEPTH_POINTS:
        raise MarkerNotFound(f"only {int(valid.sum())} depth readings on the gripper tag ({MIN_DEPTH_POINTS} needed)")
    points = backproject(np.column_stack([cols[valid], rows[valid]]).astype(np.float64), d_m[valid], K, dist)
    centre_pts = points.mean(axis=0)
    _, singular, vt = np.linalg.svd(points - centre_pts, full_matrices=False)
    normal = vt[2]
    rms = float(singular[2] / np.sqrt(len(points)))
    if rms > MAX_PLANE_RMS_M:
        raise MarkerNotFound(f"the depth on the gripper tag is not flat ({rms * 1000:.1f} mm RMS off a plane): something covers it")
    pixel = tag_centre_px(tag.corners_px)
    ray = normalized_rays(pixel[None, :], K, dist)[0]
    along = float(ray @ normal)
    if abs(along) < 1e-6:
        raise MarkerNotFound("the gripper tag is seen edge-on")
    point = ray * float(centre_pts @ normal) / along
    return MarkerSighting(pixel=pixel, point_camera_m=point, depth_points=int(valid.sum()), plane_rms_m=rms)


def find_marker(tags: list[Tag], marker_id: int, depth_mm: np.ndarray, K: np.ndarray, dist: np.ndarray) -> MarkerSighting:
    """The gripper tag (id marker_id) among a frame's detected tags, located with the depth
    (locate_marker). MarkerNotFound when it is not seen, or seen more than once (which one is the gripper?)."""
    seen = [tag for tag in tags if tag.id == marker_id]
    if not seen:
        raise MarkerNotFound(f"the gripper tag (id {marker_id}) is not in view")
    if len(seen) > 1:
        raise MarkerNotFound(f"the gripper tag (id {marker_id}) is seen {len(seen)} times")
    return locate_marker(seen[0], depth_mm, K, dist)
