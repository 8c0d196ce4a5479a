"""The board plane as the depth camera sees it: a robust plane fit over the board's pixels (objects,
the arm and everything off the board excluded), and the rigid correction that puts that plane at the
tags' z = 0.

Why: a real RGB-D camera's depth is not exactly registered with its colour camera. On the ROB 550
frames (../shared/data/rob550_dev) the depth board sits 9-15 mm behind the plane the tags' pose gives
(6-8 mm in front at another station) and is tilted ~1.5 deg; heights measured from the tags' plane
are off by that much. Heights are therefore measured from the plane fitted to each frame's own depth
(a camera knock or drift is followed), and calibration stores the correction it measured so every
depth -> world conversion (click -> world, objects, the self-filter) lands the board at z = 0.

The fit works on inverse depth: a plane n.X = D seen through pixel rays r = (x, y, 1) has
1 / depth = (n . r) / D, affine in the normalised coordinates (x, y). RANSAC on three pixels, inliers
within a height band, then least squares on the inliers (twice).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.errors import InvalidInput
from armlab.kinematics.rotations import rotation_taking


class BoardPlaneError(InvalidInput):
    """No board plane could be fitted (too few board pixels with depth, or no dominant plane)."""


@dataclass(frozen=True)
class BoardPlane:
    """The board's plane in the depth camera's frame: height(X) = normal . X + distance_m for camera
    points X (m), 0 on the board and positive toward the camera. normal: unit (3,), pointing from the
    board toward the camera; distance_m: the camera's distance from the plane. rms_m: the inliers' RMS
    distance from it (the depth noise on the board); inlier_fraction: of the pixels tried."""

    normal: np.ndarray
    distance_m: float
    rms_m: float
    inliers: int
    inlier_fraction: float

    def height_row(self) -> np.ndarray:
        """(4,) = (normal, distance): what row 2 of T_world_camera is to tag-plane heights."""
        return np.array([*self.normal, self.distance_m])

    def in_world(self, T_world_camera: np.ndarray) -> tuple[np.ndarray, float]:
        """(unit normal, d) of the plane in world coordinates: normal . P + d = 0 on the plane."""
        n_w = T_world_camera[:3, :3] @ self.normal
        # A camera point X maps to P = R X + t; n.X + D = 0 <=> (R n).(P - t) + D = 0.
        return n_w, float(self.distance_m - n_w @ T_world_camera[:3, 3])


def fit_inverse_depth_plane(
    x: np.ndarray, y: np.ndarray, depth_m: np.ndarray, inlier_m: float, iterations: int = 48, seed: int = 0,
    min_fraction: float = 0.3,
) -> BoardPlane:
    """Robust plane through camera points depth * (x, y, 1) (1-D arrays of normalised coordinates and
    depths in metres, board candidates only). BoardPlaneError when fewer than min_fraction of them lie
    within inlier_m of the best plane."""
    x = np.asarray(x, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    d = np.asarray(depth_m, dtype=np.float64).ravel()
    n = d.size
    if n < 50:
        raise BoardPlaneError(f"only {n} board pixels have depth; a plane fit needs at least 50")
    A = np.column_stack([x, y, np.ones(n)])
    w = 1.0 / d
    rng = np.random.default_rng(seed)

    def heights(coef: np.ndarray) -> np.ndarray:
        # n.X + D with n = -coef/|coef|, D = 1/|coef|: (1 - depth * coef.r) / |coef|.
        norm = math.sqrt(float(coef @ coef))
        return (1.0 - d * (A @ coef)) / norm

    best, best_count = None, -1
    samples = rng.integers(0, n, size=(iterations, 3))
    try:  # every sample's plane in one call (the same LAPACK solve per 3 x 3 system), one by one if any is singular
        solutions = np.linalg.solve(A[samples], w[samples][..., None])[..., 0]
        # The plane must face the camera.
        valid = solutions[np.isfinite(solutions).all(axis=1) & (solutions[:, 2] > 0)]
    except np.linalg.LinAlgError:
        coefs = [_solve_or_none(A[idx], w[idx]) for idx in samples]
        valid = np.array([coef for coef in coefs if coef is not None and np.all(np.isfinite(coef)) and coef[2] > 0]).reshape(-1, 3)
    if len(valid):
        # Every valid sample's inliers counted in one pass over the points (in place: no image-sized temporaries).
        C = np.ascontiguousarray(valid.T)  # (3, k)
        residual = A @ C
        residual *= d[:, None]
        np.subtract(1.0, residual, out=residual)
        residual /= np.sqrt(np.einsum("ij,ij->j", C, C))
        # Inliers per sample as one product (whole numbers, exact), far cheaper than a column-wise count of the (N, k) mask.
        counts = np.ones(n) @ (np.abs(residual, out=residual) < inlier_m).astype(np.float64)
        first_best = int(np.argmax(counts))  # the first of equals, as one by one
        best, best_count = valid[first_best], int(counts[first_best])
    if best is None or best_count < min_fraction * n:
        raise BoardPlaneError(f"no dominant board plane in the depth: the best holds {max(best_count, 0)} of {n} board pixels")
    inliers = np.abs(heights(best)) < inlier_m
    coef = best
    for _ in range(2):  # least squares on the inliers: coef . X = 1 for camera points X on the plane
        coef = _plane_lstsq(A.compress(inliers, axis=0) * d[inliers][:, None])
        inliers = np.abs(heights(coef)) < inlier_m
    h = heights(coef)[inliers]
    norm = math.sqrt(float(coef @ coef))
    return BoardPlane(normal=-coef / norm, distance_m=1.0 / norm, rms_m=float(np.sqrt(np.mean(h * h))),
                      inliers=int(inliers.sum()), inlier_fraction=float(inliers.mean()))


def _solve_or_none(M: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    try:
        return np.linalg.solve(M, b)
    except np.linalg.LinAlgError:
        return None


def _plane_lstsq(points: np.ndarray) -> np.ndarray:
    """c minimising sum (c . X_i - 1)^2 over camera points X (N, 3): the normal equations (3 x 3),
    far cheaper than an SVD of the N x 3 matrix; the points are ~1 m away, so they are well conditioned."""
    return np.linalg.solve(points.T @ points, points.sum(axis=0))


def board_pixel_mask(shape: tuple[int, int], K: np.ndarray, T_world_camera: np.ndarray, x_range_m, y_range_m,
                     step: int = 1, margin_m: float = 0.02) -> np.ndarray:
    """(H', W') bool of every step-th pixel whose ray meets the tags' plane z = 0 inside the board's
    rectangle shrunk by margin_m (lens distortion ignored: a margin's worth at the corners)."""
    h, w = shape
    us = (np.arange(w) * step - K[0, 2]) / K[0, 0]
    vs = (np.arange(h) * step - K[1, 2]) / K[1, 1]
    R, t = T_world_camera[:3, :3], T_world_camera[:3, 3]
    rx, ry, rz = (R[:, 0][:, None, None] * us[None, None, :] + R[:, 1][:, None, None] * vs[None, :, None] + R[:, 2][:, None, None])
    with np.errstate(divide="ignore", invalid="ignore"):
        s = -t[2] / rz
        X, Y = t[0] + s * rx, t[1] + s * ry
        return ((s > 0) & (X > x_range_m[0] + margin_m) & (X < x_range_m[1] - margin_m)
                & (Y > y_range_m[0] + margin_m) & (Y < y_range_m[1] - margin_m))


def fit_board_plane(
    depth_m: np.ndarray, x: np.ndarray, y: np.ndarray, tag_heights_m: np.ndarray, on_board: np.ndarray,
    window_m: float, inlier_m: float, sample_step: int = 2, exclude: np.ndarray | None = None, seed: int = 0,
    min_fraction: float = 0.5,
) -> BoardPlane:
    """The board plane from one depth image (any resolution; all arrays the same shape): pixels on the
    board (on_board), with a reading, whose height above the tags' plane (tag_heights_m) is within
    window_m (what the depth camera's offset can be; cubes and the arm stand taller), and not excluded
    (e.g. the robot's mask). RANSAC on every sample_step-th candidate, least squares on all inliers."""
    with np.errstate(invalid="ignore"):
        cand = on_board & (depth_m > 0) & (np.abs(tag_heights_m) < window_m)
    if exclude is not None:
        cand &= ~exclude
    ys, xs = np.nonzero(cand)
    if ys.size < 50:
        raise BoardPlaneError(f"only {ys.size} board pixels have depth within {window_m * 1000:.0f} mm of the tags' plane")
    return _fit_candidates(x[ys, xs], y[ys, xs], depth_m[ys, xs], inlier_m, sample_step, seed, min_fraction)


def _fit_candidates(xx: np.ndarray, yy: np.ndarray, dd: np.ndarray, inlier_m: float, sample_step: int, seed: int,
                    min_fraction: float) -> BoardPlane:
    """fit_board_plane on its candidates (1-D normalised coordinates and depths, in image order)."""
    sub = slice(None, None, max(1, int(sample_step)))
    # RANSAC on a quarter of the candidates (thousands of pixels: the plane is fixed long before).
    rough = fit_inverse_depth_plane(xx[sub][::2], yy[sub][::2], dd[sub][::2], inlier_m, iterations=16, seed=seed,
                                    min_fraction=min_fraction)
    # Refit on the candidates (every sample_step-th), starting from the rough plane's inliers.
    xx, yy, dd = xx[sub], yy[sub], dd[sub]
    h = dd * (rough.normal[0] * xx + rough.normal[1] * yy + rough.normal[2]) + rough.distance_m
    keep = np.abs(h) < inlier_m
    coef = _plane_lstsq(np.column_stack([xx[keep], yy[keep], np.ones(int(keep.sum()))]) * dd[keep][:, None])
    norm = math.sqrt(float(coef @ coef))
    normal, distance = -coef / norm, 1.0 / norm
    h = dd * (normal[0] * xx + normal[1] * yy + normal[2]) + distance
    inl = np.abs(h) < inlier_m
    return BoardPlane(normal=normal, distance_m=distance, rms_m=float(np.sqrt(np.mean(h[inl] ** 2))),
                      inliers=int(inl.sum()), inlier_fraction=float(inl.mean()))


@dataclass(frozen=True)
class DepthCorrection:
    """How the depth camera's board plane sits against the tags' plane, and the rigid world -> world
    correction (4x4) that moves the former onto the latter: rotation about the work area's centre by
    the tilt, then a shift along z. offset_m: the depth plane's height above the tags' plane at that
    centre (negative = behind it, away from the camera); tilt_deg: the angle between the planes."""

    offset_m: float
    tilt_deg: float
    T_correction: np.ndarray

    def describe(self) -> str:
        where = "behind" if self.offset_m < 0 else "in front of"
        return f"depth {abs(self.offset_m) * 1000:.1f} mm {where} the tags' plane, tilted {self.tilt_deg:.2f} deg"


def depth_correction(plane: BoardPlane, T_world_camera: np.ndarray, centre_xy_m) -> DepthCorrection:
    """The correction that puts the depth board plane (camera frame) on the world's z = 0 when depth
    points are mapped by T_correction @ T_world_camera; centre_xy_m: where the offset is measured and
    about which the tilt is undone (the board tags' centroid: the work area)."""
    n_w, d = plane.in_world(T_world_camera)
    if n_w[2] < 0:
        n_w, d = -n_w, -d
    cx, cy = float(centre_xy_m[0]), float(centre_xy_m[1])
    z0 = -(d + n_w[0] * cx + n_w[1] * cy) / n_w[2]  # the depth plane's height at the centre
    tilt = math.acos(min(1.0, float(n_w[2])))
    R = rotation_taking(n_w, [0.0, 0.0, 1.0])
    p0 = np.array([cx, cy, z0])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.array([cx, cy, 0.0]) - R @ p0
    return DepthCorrection(offset_m=float(z0), tilt_deg=math.degrees(tilt), T_correction=T)


def correction_from_dict(data: dict | None) -> DepthCorrection | None:
    if not data:
        return None
    T = np.asarray(data["T_correction"], dtype=np.float64)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)) or not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6):
        raise ValueError("depth_correction.T_correction must be a finite rigid 4x4 transform")
    return DepthCorrection(float(data["offset_m"]), float(data["tilt_deg"]), T)


def correction_to_dict(c: DepthCorrection | None) -> dict | None:
    return None if c is None else {"offset_m": c.offset_m, "tilt_deg": c.tilt_deg, "T_correction": c.T_correction.tolist()}


def apply_correction(T_world_camera: np.ndarray, correction: DepthCorrection | None) -> np.ndarray:
    """T_world_depth: depth-camera points -> world (T_world_camera when there is no correction)."""
    return T_world_camera if correction is None else correction.T_correction @ T_world_camera


__all__ = ["BoardPlane", "BoardPlaneError", "DepthCorrection", "apply_correction", "board_pixel_mask", "depth_correction",
           "fit_board_plane", "fit_inverse_depth_plane"]


class BoardPlaneFitter:
    """fit_board_plane for one calibration and image size, with its per-pixel inputs computed once:
    every step-th pixel's normalised coordinates (undistorted when `undistort`, else the pinhole's,
    matching heights computed without distortion), the board mask and the tag-plane height terms."""

    def __init__(self, K: np.ndarray, dist: np.ndarray, T_world_camera: np.ndarray, width: int, height: int,
                 x_range_m, y_range_m, step: int = 4, undistort: bool = False) -> None:
        self.key = (K.tobytes(), np.asarray(dist).tobytes(), T_world_camera.tobytes(), width, height, step, undistort)
        self.step = step
        h, w = -(-height // step), -(-width // step)
        us = np.arange(w, dtype=np.float64) * step
        vs = np.arange(h, dtype=np.float64) * step
        if undistort and np.any(np.asarray(dist) != 0):
            import cv2

            grid = np.stack(np.meshgrid(us, vs), axis=-1).reshape(-1, 1, 2)
            und = cv2.undistortPoints(grid, K, np.asarray(dist, dtype=np.float64)).reshape(h, w, 2)
            self.x, self.y = und[..., 0], und[..., 1]
        else:
            self.x = np.broadcast_to(((us - K[0, 2]) / K[0, 0])[None, :], (h, w))
            self.y = np.broadcast_to(((vs - K[1, 2]) / K[1, 1])[:, None], (h, w))
        r3 = T_world_camera[2, :3]
        self.tag_coefficients = r3[0] * self.x + r3[1] * self.y + r3[2]
        self.tag_t = float(T_world_camera[2, 3])
        self.on_board = board_pixel_mask((h, w), K, T_world_camera, x_range_m, y_range_m, step)
        # The board's pixels (flat indices, image order) and their terms: a frame's candidates are looked for there only.
        self.board_flat = np.flatnonzero(self.on_board)
        self.board_x, self.board_y = self.x.ravel()[self.board_flat], self.y.ravel()[self.board_flat]
        self.board_tag_coefficients = self.tag_coefficients.ravel()[self.board_flat]

    def fit(self, depth_m_small: np.ndarray, window_m: float, inlier_m: float, exclude_small: np.ndarray | None = None,
            min_fraction: float = 0.5) -> BoardPlane:
        """The board plane of a depth image already sampled at this fitter's step (metres, 0 = none):
        fit_board_plane over the board's pixels only (the same candidates in the same order)."""
        depth = np.take(depth_m_small, self.board_flat)
        with np.errstate(invalid="ignore"):
            cand = (depth > 0) & (np.abs(depth * self.board_tag_coefficients + self.tag_t) < window_m)
        if exclude_small is not None:
            cand &= ~np.take(exclude_small, self.board_flat)
        count = int(np.count_nonzero(cand))
        if count < 50:
            raise BoardPlaneError(f"only {count} board pixels have depth within {window_m * 1000:.0f} mm of the tags' plane")
        return _fit_candidates(self.board_x[cand], self.board_y[cand], depth[cand], inlier_m, 2, 0, min_fraction)
