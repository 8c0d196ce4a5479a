"""Pure camera geometry: rigid 3-D fits, back-projection, ray-plane intersection, projection.

Frames follow the names: T_world_camera maps camera coordinates (OpenCV axes: x right, y down,
z forward) to world coordinates. Depth is along the optical axis, as RGB-D cameras report it.
"""

from __future__ import annotations

import cv2
import numpy as np

from armlab.errors import InvalidInput


def as_points(points: np.ndarray, dim: int, name: str = "points") -> np.ndarray:
    """Points as a finite float (N, dim) array; ValueError on the wrong shape or NaN/inf."""
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == dim:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise InvalidInput(f"{name} must have shape (N, {dim}), got {np.shape(points)}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInput(f"{name} contains NaN or infinity")
    return arr


def rigid_transform_3d(points_src: np.ndarray, points_dst: np.ndarray) -> np.ndarray:
    """The 4x4 rigid transform T minimising sum |T src_i - dst_i|^2 (Kabsch/SVD, reflection fixed).

    With src in the camera frame and dst in the world frame, the result is T_world_camera.
    """
    src = as_points(points_src, 3, "points_src")
    dst = as_points(points_dst, 3, "points_dst")
    if src.shape != dst.shape:
        raise InvalidInput(f"point sets differ in shape: {src.shape} vs {dst.shape}")
    if src.shape[0] < 3:
        raise InvalidInput(f"a rigid fit needs at least 3 points, got {src.shape[0]}")
    mu_src, mu_dst = src.mean(axis=0), dst.mean(axis=0)
    src_c, dst_c = src - mu_src, dst - mu_dst
    if np.linalg.matrix_rank(src_c, tol=1e-9) < 2 or np.linalg.matrix_rank(dst_c, tol=1e-9) < 2:
        raise InvalidInput("points are collinear: the rotation is not determined")
    u, _, vt = np.linalg.svd(src_c.T @ dst_c)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rotation = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    transform = np.eye(4)
    transform[:3, :3] = rotation
    transform[:3, 3] = mu_dst - rotation @ mu_src
    return transform


def transform_points(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply a 4x4 transform to (N, 3) points."""
    pts = as_points(points, 3)
    return pts @ T[:3, :3].T + T[:3, 3]


def invert_transform(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid 4x4 transform."""
    inv = np.eye(4)
    inv[:3, :3] = T[:3, :3].T
    inv[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return inv


def normalized_rays(pixels: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Undistorted normalised image coordinates (N, 3) = (x, y, 1) for pixels (N, 2)."""
    px = as_points(pixels, 2, "pixels")
    if np.any(np.asarray(dist) != 0.0):
        xy = cv2.undistortPoints(px.reshape(-1, 1, 2), K, np.asarray(dist, dtype=np.float64)).reshape(-1, 2)
    else:
        xy = (px - K[:2, 2]) / np.array([K[0, 0], K[1, 1]])
    return np.hstack([xy, np.ones((xy.shape[0], 1))])


def backproject(pixels: np.ndarray, depth_m: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Camera-frame points (N, 3) for pixels (N, 2) with depth along the optical axis (N,) in metres."""
    depth = np.asarray(depth_m, dtype=np.float64).reshape(-1)
    rays = normalized_rays(pixels, K, dist)
    if depth.shape[0] != rays.shape[0]:
        raise InvalidInput(f"{rays.shape[0]} pixels but {depth.shape[0]} depths")
    return rays * depth[:, None]


def intersect_rays_with_plane(T_world_camera: np.ndarray, rays_camera: np.ndarray, plane_z_m: float) -> np.ndarray:
    """World points (N, 3) where camera rays (N, 3) meet the horizontal plane z = plane_z_m.

    ValueError if a ray is parallel to the plane or meets it behind the camera.
    """
    origin = T_world_camera[:3, 3]
    directions = rays_camera @ T_world_camera[:3, :3].T
    dz = directions[:, 2]
    if np.any(np.abs(dz) < 1e-9):
        raise InvalidInput("a viewing ray is parallel to the plane")
    s = (plane_z_m - origin[2]) / dz
    if np.any(s <= 0):
        raise InvalidInput(f"the plane z = {plane_z_m} m is behind the camera for this pixel")
    return origin + directions * s[:, None]


def project_points(T_world_camera: np.ndarray, K: np.ndarray, dist: np.ndarray, points_m: np.ndarray) -> np.ndarray:
    """Pixels (N, 2) of world points (N, 3) through the camera (with lens distortion)."""
    return project_points_rt(projection_pose(T_world_camera), K, dist, points_m)


def projection_pose(T_world_camera: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rvec, tvec): the world -> camera pose as cv2.projectPoints takes it (what project_points computes
    per call; a caller projecting every frame through one calibration keeps it)."""
    T_camera_world = invert_transform(T_world_camera)
    rvec, _ = cv2.Rodrigues(T_camera_world[:3, :3])
    return rvec, T_camera_world[:3, 3]


def project_points_rt(pose: tuple[np.ndarray, np.ndarray], K: np.ndarray, dist: np.ndarray, points_m: np.ndarray) -> np.ndarray:
    """project_points with the pose given as projection_pose(T_world_camera)."""
    pts = as_points(points_m, 3, "points_m")
    pixels, _ = cv2.projectPoints(pts.reshape(-1, 1, 3), pose[0], pose[1], K, np.asarray(dist, dtype=np.float64))
    return pixels.reshape(-1, 2)


def board_homography(T_world_camera: np.ndarray, K: np.ndarray, plane_z_m: float = 0.0) -> np.ndarray:
    """3x3 H mapping points (x, y, 1) of the plane z = plane_z_m (metres) to undistorted pixels (u, v, 1)."""
    H = PlaneCamera(T_world_camera, K, np.zeros(5)).homography(plane_z_m)
    return H / H[2, 2]


class PlaneCamera:
    """A calibrated camera mapping between pixels and horizontal planes z = const, with its pose
    inverted and its distortion checked once (build one per frame, not one per point set).
    Without distortion a plane maps through one homography; with it, through full projection and rays."""

    def __init__(self, T_world_camera: np.ndarray, K: np.ndarray, dist: np.ndarray) -> None:
        self.T_world_camera = T_world_camera
        self.T_camera_world = invert_transform(T_world_camera)
        self.K = K
        self.dist = dist
        self.distorted = bool(np.any(np.asarray(dist) != 0))

    def homography(self, plane_z_m: float) -> np.ndarray:
        """The unnormalised homography (x, y, 1) on the plane z = plane_z_m -> undistorted pixel."""
        T = self.T_camera_world
        M = np.empty((3, 3))
        M[:, 0] = T[:3, 0]
        M[:, 1] = T[:3, 1]
        M[:, 2] = T[:3, 2] * plane_z_m + T[:3, 3]
        return self.K @ M

    def project(self, points_xy: np.ndarray, plane_z_m: float, H: np.ndarray | None = None) -> np.ndarray:
        """Pixels (N, 2) of points (N, 2) on the plane z = plane_z_m: a homography without lens distortion
        (cheap enough for per-frame drawing), full projection with it. H: self.homography(plane_z_m), if the caller has it."""
        pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
        if self.distorted:
            return project_points(self.T_world_camera, self.K, self.dist, np.column_stack([pts, np.full(len(pts), plane_z_m)]))
        H = self.homography(plane_z_m) if H is None else H
        H = H / H[2, 2]
        uvw = pts @ H[:, :2].T + H[:, 2]
        return dehomogenise(uvw)

    def to_plane(self, pixels: np.ndarray, plane_z_m: float, H: np.ndarray | None = None) -> np.ndarray:
        """World (x, y) (N, 2) of pixels (N, 2) on the plane z = plane_z_m: one inverse homography when
        the lens has no distortion, else undistorted rays meeting the plane. H: as for project."""
        if self.distorted:
            return intersect_rays_with_plane(self.T_world_camera, normalized_rays(pixels, self.K, self.dist), plane_z_m)[:, :2]
        H_inv = np.linalg.inv(self.homography(plane_z_m)) if H is None else inverse_homography(H)
        xyw = pixels @ H_inv[:, :2].T + H_inv[:, 2]
        return dehomogenise(xyw)


def dehomogenise(points_h: np.ndarray) -> np.ndarray:
    """(N, 2) = points_h[:, :2] / points_h[:, 2:3] for homogeneous points (N, 3): the same divisions, column by
    column (a broadcast over (N, 2) strided views costs several times more on a face's thousands of points)."""
    out = np.empty((len(points_h), 2), points_h.dtype if points_h.dtype.kind == "f" else np.float64)
    np.divide(points_h[:, 0], points_h[:, 2], out=out[:, 0])
    np.divide(points_h[:, 1], points_h[:, 2], out=out[:, 1])
    return out


_LAST_INVERSE: tuple[np.ndarray | None, np.ndarray | None] = (None, None)


def inverse_homography(H: np.ndarray) -> np.ndarray:
    """np.linalg.inv(H), remembered for the last H object given: a face's plane homography is inverted
    for its points, then again for its outline's hull and its parts' (the same array object: treat it as
    read-only). One (H, inverse) tuple, swapped whole, so concurrent callers never mix two entries."""
    global _LAST_INVERSE
    last_H, last_inverse = _LAST_INVERSE
    if last_H is H:
        return last_inverse
    inverse = np.linalg.inv(H)
    _LAST_INVERSE = (H, inverse)
    return inverse


def height_coefficients(shape: tuple[int, int], K: np.ndarray, T_world_camera: np.ndarray, step: int = 1) -> np.ndarray:
    """Per pixel of an (H, W) depth image (every `step`-th pixel of the camera's): the factor c of
    z = depth * c + t_z, i.e. r3 . K^-1 [u, v, 1], computed separably. Depends only on the calibration."""
    h, w = shape
    us = (np.arange(w, dtype=np.float32) * step - K[0, 2]) / K[0, 0]
    vs = (np.arange(h, dtype=np.float32) * step - K[1, 2]) / K[1, 1]
    r3 = T_world_camera[2, :3].astype(np.float32)
    return r3[0] * us[None, :] + (r3[1] * vs[:, None] + r3[2])


def height_map_m(
    depth_m: np.ndarray, K: np.ndarray, T_world_camera: np.ndarray, step: int = 1, coefficients: np.ndarray | None = None
) -> np.ndarray:
    """World z (metres) of every `step`-th pixel of a depth image (metres, 0 = none -> NaN).

    z = depth * (r3 . K^-1 [u, v, 1]) + t_z, computed separably so it costs a few operations per pixel
    (coefficients: height_coefficients for this shape and calibration, if the caller keeps them).
    Lens distortion is ignored here (it is applied exactly where a position is reported).
    """
    d = np.asarray(depth_m, dtype=np.float32)[::step, ::step]
    if coefficients is None:
        coefficients = height_coefficients(d.shape, K, T_world_camera, step)
    z = np.multiply(d, coefficients)  # then in place: one image-sized array, no temporaries
    z += np.float32(T_world_camera[2, 3])
    np.copyto(z, np.nan, where=d <= 0)
    return z
