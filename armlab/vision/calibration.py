"""Automatic extrinsic calibration from the four board tags: PnP on all tag corners, a depth-based
rigid-fit cross-check, the board homography and grid projection; saved and reloaded as JSON."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.vision.board_plane import (
    BoardPlaneError,
    BoardPlaneFitter,
    DepthCorrection,
    apply_correction,
    correction_from_dict,
    correction_to_dict,
    depth_correction,
)
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import (
    backproject,
    board_homography,
    invert_transform,
    project_points,
    rigid_transform_3d,
    transform_points,
)
from armlab.vision.tags import Tag, check_color_image, detect_tags


class CalibrationError(ValueError):
    """A calibration could not be made or would be wrong; the message says why in one sentence."""


@dataclass(frozen=True)
class Calibration:
    """The camera's pose in the world plus its intrinsics, with the quality figures that vouch for it."""

    T_world_camera: np.ndarray
    K: np.ndarray
    dist: np.ndarray
    width: int
    height: int
    reprojection_error_px: float
    depth_check_error_m: float | None = None
    T_world_camera_depth: np.ndarray | None = None
    tag_ids: tuple[int, ...] = ()
    created_s: float = field(default_factory=time.time)
    # How the depth camera's board plane sits against the tags' plane (board_plane.DepthCorrection):
    # None = no correction measured (no depth, or an older calibration): depth maps through T_world_camera.
    depth_correction: DepthCorrection | None = None

    @property
    def T_world_depth(self) -> np.ndarray:
        """Depth-camera points (back-projected with K, dist) -> world: T_world_camera corrected by the
        board plane the depth showed at calibration (so the board's depth lands at z = 0)."""
        return apply_correction(self.T_world_camera, self.depth_correction)

    @property
    def depth_offset_m(self) -> float | None:
        """The depth board plane's height above the tags' plane at the tags' centre (negative: behind)."""
        return None if self.depth_correction is None else self.depth_correction.offset_m

    @property
    def depth_tilt_deg(self) -> float | None:
        return None if self.depth_correction is None else self.depth_correction.tilt_deg

    @property
    def camera_position_m(self) -> np.ndarray:
        return self.T_world_camera[:3, 3].copy()

    @property
    def T_camera_world(self) -> np.ndarray:
        return invert_transform(self.T_world_camera)

    @property
    def H_image_board(self) -> np.ndarray:
        """Homography from board-plane metres (x, y, 1) to undistorted pixels."""
        return board_homography(self.T_world_camera, self.K)

    def to_dict(self) -> dict:
        return {
            "T_world_camera": self.T_world_camera.tolist(),
            "K": self.K.tolist(),
            "dist": np.asarray(self.dist).ravel().tolist(),
            "width": self.width,
            "height": self.height,
            "reprojection_error_px": self.reprojection_error_px,
            "depth_check_error_m": self.depth_check_error_m,
            "T_world_camera_depth": None if self.T_world_camera_depth is None else self.T_world_camera_depth.tolist(),
            "tag_ids": list(self.tag_ids),
            "camera_position_m": self.camera_position_m.tolist(),
            "created_s": self.created_s,
            "depth_correction": correction_to_dict(self.depth_correction),
            "depth_model": None if self.depth_correction is None else self.depth_correction.describe(),
        }

    @classmethod
    def from_dict(cls, data: dict) -> Calibration:
        """Rebuild from to_dict(); CalibrationError naming the field when it is missing or malformed."""
        try:
            T = _matrix(data["T_world_camera"], (4, 4), "T_world_camera")
            K = _matrix(data["K"], (3, 3), "K")
            dist = np.asarray(data.get("dist", [0.0] * 5), dtype=np.float64).ravel()
            T_depth = data.get("T_world_camera_depth")
            depth_err = data.get("depth_check_error_m")
            cal = cls(
                T_world_camera=T,
                K=K,
                dist=dist,
                width=int(data["width"]),
                height=int(data["height"]),
                reprojection_error_px=float(data["reprojection_error_px"]),
                depth_check_error_m=None if depth_err is None else float(depth_err),
                T_world_camera_depth=None if T_depth is None else _matrix(T_depth, (4, 4), "T_world_camera_depth"),
                tag_ids=tuple(int(i) for i in data.get("tag_ids", ())),
                created_s=float(data.get("created_s", time.time())),
                depth_correction=_correction(data.get("depth_correction")),
            )
        except KeyError as error:
            raise CalibrationError(f"calibration data lacks the field {error.args[0]!r}") from error
        except (TypeError, ValueError) as error:
            if isinstance(error, CalibrationError):
                raise
            raise CalibrationError(f"calibration data is malformed: {error}") from error
        if not np.all(np.isfinite(dist)) or cal.width <= 0 or cal.height <= 0:
            raise CalibrationError("calibration data has a non-finite distortion or a non-positive image size")
        if not np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-6) or not np.allclose(T[3], [0, 0, 0, 1]):
            raise CalibrationError("T_world_camera is not a rigid transform")
        return cal

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2))

    @classmethod
    def load(cls, path: str | Path) -> Calibration:
        try:
            data = json.loads(Path(path).read_text())
        except (OSError, json.JSONDecodeError) as error:
            raise CalibrationError(f"cannot read calibration {path}: {error}") from error
        if not isinstance(data, dict):
            raise CalibrationError(f"calibration {path} is not a JSON object")
        return cls.from_dict(data)


def _correction(value) -> DepthCorrection | None:
    try:
        return correction_from_dict(value)
    except (KeyError, TypeError, ValueError) as error:
        raise CalibrationError(f"calibration data: depth_correction is malformed ({error})") from error


def _matrix(value, shape: tuple[int, int], name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != shape:
        raise CalibrationError(f"{name} must be {shape[0]}x{shape[1]}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CalibrationError(f"{name} contains NaN or infinity")
    return arr


def _board_correspondences(tags: list[Tag], cfg: PerceptionConfig) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """World corners (N, 3) and their pixels (N, 2) for the board tags found (first of each id)."""
    seen: dict[int, Tag] = {}
    for tag in tags:
        if tag.id in cfg.tags.board_tags and tag.id not in seen:
            seen[tag.id] = tag
    ids = tuple(sorted(seen))
    if not ids:
        return np.zeros((0, 3)), np.zeros((0, 2)), ids
    world = np.vstack([cfg.board_tag_corners_m(i) for i in ids])
    pixels = np.vstack([seen[i].corners_px for i in ids])
    return world, pixels, ids


def solve_board_pose(tags: list[Tag], K: np.ndarray, dist: np.ndarray, cfg: PerceptionConfig) -> tuple[np.ndarray, float, tuple[int, ...]]:
    """T_world_camera from the board-tag corners by PnP, its RMS reprojection error (px) and the ids used."""
    world, pixels, ids = _board_correspondences(tags, cfg)
    expected = sorted(cfg.tags.board_tags)
    if len(ids) < 3:
        missing = [i for i in expected if i not in ids]
        raise CalibrationError(
            f"calibration needs at least 3 of the board tags {expected}; found {list(ids) or 'none'} (missing {missing})"
        )
    ok, rvec, tvec = cv2.solvePnP(world, pixels, K, dist, flags=cv2.SOLVEPNP_SQPNP)
    if not ok:
        raise CalibrationError("PnP found no camera pose for the board tags")
    rvec, tvec = cv2.solvePnPRefineLM(world, pixels, K, dist, rvec, tvec)
    rotation, _ = cv2.Rodrigues(rvec)
    T_camera_world = np.eye(4)
    T_camera_world[:3, :3] = rotation
    T_camera_world[:3, 3] = tvec.ravel()
    T_world_camera = invert_transform(T_camera_world)
    projected = project_points(T_world_camera, K, dist, world)
    error = float(np.sqrt(np.mean(np.sum((projected - pixels) ** 2, axis=1))))
    return T_world_camera, error, ids


def depth_at(depth_mm: np.ndarray, u: float, v: float, radius: int = 2) -> float:
    """Median of the valid depth readings (mm) in a (2r+1)^2 window at (u, v); 0 if there are none."""
    h, w = depth_mm.shape
    ui, vi = int(round(u)), int(round(v))
    if not (0 <= ui < w and 0 <= vi < h):
        return 0.0
    window = depth_mm[max(0, vi - radius) : vi + radius + 1, max(0, ui - radius) : ui + radius + 1]
    valid = window[window > 0]
    return float(np.median(valid)) if valid.size else 0.0


def depth_cross_check(
    tags: list[Tag], depth_mm: np.ndarray, K: np.ndarray, dist: np.ndarray, cfg: PerceptionConfig, T_world_camera: np.ndarray,
    T_world_depth: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """Independent pose from depth: back-project the board-tag centres and fit a rigid transform (SVD).

    Returns that T_world_camera and the RMS distance (m) between the tag centres mapped through the
    depth model (T_world_depth: the PnP pose with the board plane's correction; T_world_camera when
    None) and their true world positions: large when PnP or the depth disagree with the board.
    """
    centres_px, centres_world = [], []
    for tag in tags:
        if tag.id in cfg.tags.board_tags and tag.id not in [c[0] for c in centres_world]:
            d = depth_at(depth_mm, *tag.center_px)
            if d > 0:
                centres_px.append(tag.center_px)
                x, y = cfg.tags.board_tags[tag.id]
                centres_world.append((tag.id, np.array([x, y, 0.0])))
    if len(centres_px) < 3:
        raise CalibrationError(f"the depth image has readings at only {len(centres_px)} board-tag centres; 3 are needed")
    pixels = np.array(centres_px)
    depths_m = np.array([depth_at(depth_mm, *p) for p in pixels]) / 1000.0
    camera_pts = backproject(pixels, depths_m, K, dist)
    world_pts = np.array([w for _, w in centres_world])
    T_depth = rigid_transform_3d(camera_pts, world_pts)
    residual = transform_points(T_world_camera if T_world_depth is None else T_world_depth, camera_pts) - world_pts
    return T_depth, float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))


def calibrate_extrinsics(
    color_bgr: np.ndarray,
    intrinsics: Intrinsics,
    cfg: PerceptionConfig,
    depth_mm: np.ndarray | None = None,
    tags: list[Tag] | None = None,
) -> Calibration:
    """Find the board tags and solve the camera pose; with depth, cross-check it independently.

    Raises CalibrationError (a ValueError) with a clear sentence rather than return a bad calibration.
    """
    try:
        check_color_image(color_bgr)
    except ValueError as error:
        raise CalibrationError(str(error)) from error
    h, w = color_bgr.shape[:2]
    if (w, h) != (intrinsics.width, intrinsics.height):
        raise CalibrationError(f"image is {w}x{h} but the intrinsics are for {intrinsics.width}x{intrinsics.height}")
    if depth_mm is not None and (depth_mm.shape != (h, w) or depth_mm.dtype.kind not in "ui"):
        raise CalibrationError(f"depth must be an integer (H, W) = ({h}, {w}) image in mm, got {depth_mm.shape} {depth_mm.dtype}")
    K = intrinsics.K
    dist = np.asarray(intrinsics.dist, dtype=np.float64)
    if tags is None:
        tags = detect_tags(color_bgr, cfg)
    T_world_camera, error_px, ids = solve_board_pose(tags, K, dist, cfg)
    limit_px = cfg.calibration.max_reprojection_error_px
    if error_px > limit_px:
        raise CalibrationError(f"tag reprojection error {error_px:.2f} px exceeds {limit_px} px: a tag is misdetected or misplaced")
    if T_world_camera[2, 3] <= 0:
        raise CalibrationError("the solved camera is below the board: the tag layout does not match the config")
    T_depth, depth_error, correction = None, None, None
    if depth_mm is not None:
        correction = measure_depth_correction(depth_mm, K, dist, T_world_camera, cfg)
        T_depth, depth_error = depth_cross_check(tags, depth_mm, K, dist, cfg, T_world_camera, apply_correction(T_world_camera, correction))
        limit_m = cfg.calibration.max_depth_check_error_m
        if depth_error > limit_m:
            raise CalibrationError(
                f"depth cross-check disagrees with the tag pose by {depth_error * 1000:.1f} mm (limit {limit_m * 1000:.0f} mm)"
            )
    return Calibration(
        T_world_camera=T_world_camera,
        K=K,
        dist=dist,
        width=w,
        height=h,
        reprojection_error_px=error_px,
        depth_check_error_m=depth_error,
        T_world_camera_depth=T_depth,
        tag_ids=ids,
        depth_correction=correction,
    )


def measure_depth_correction(
    depth_mm: np.ndarray, K: np.ndarray, dist: np.ndarray, T_world_camera: np.ndarray, cfg: PerceptionConfig
) -> DepthCorrection | None:
    """The depth camera's offset and tilt against the tags' plane (board_plane.depth_correction), from
    the board plane fitted in this depth image (undistorted rays, every 4th pixel); None when the board
    plane is disabled in the config. CalibrationError when no board plane shows in the depth."""
    bp = cfg.board_plane
    if not bp.enabled:
        return None
    h, w = depth_mm.shape
    fitter = BoardPlaneFitter(K, dist, T_world_camera, w, h, cfg.board.x_range_m, cfg.board.y_range_m, step=4, undistort=True)
    small = depth_mm[::4, ::4].astype(np.float64) / 1000.0
    try:
        plane = fitter.fit(small, bp.window_m, bp.inlier_m, min_fraction=bp.min_inlier_fraction)
    except BoardPlaneError:
        return None  # no board near the tags' plane in this depth: the cross-check says how far off it is
    centre = np.mean(np.array(list(cfg.tags.board_tags.values()), dtype=np.float64), axis=0)
    return depth_correction(plane, T_world_camera, centre)


def project_grid(cal: Calibration, cfg: PerceptionConfig) -> np.ndarray:
    """Pixels (N, 2) of the board's grid points, for drawing and visual validation."""
    return project_points(cal.T_world_camera, cal.K, cal.dist, cfg.board.grid_points_m())
