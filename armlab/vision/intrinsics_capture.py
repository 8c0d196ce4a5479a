"""A guided checkerboard capture for intrinsic calibration: each view is checked (board found, sharp
enough, not a duplicate of an earlier view) before it is kept; coverage shows which image regions the
kept views reach; the solve (OpenCV's calibrateCamera) reports K, distortion, the RMS and one error per
view, and refuses too few views or too high an error. Pure: images in, results or IntrinsicsRejected out.

Config: config/intrinsics.yaml (`target:` the printed board, `capture:` the limits)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated

import cv2
import numpy as np
from pydantic import Field

from armlab.config import StrictModel, config_dir, load_config
from armlab.errors import InvalidInput
from armlab.vision.intrinsics import IntrinsicCalibration


class IntrinsicsRejected(InvalidInput):
    """A view or a solve refused, with a short wire code: not_found, blurry, duplicate, size,
    too_few_views, error_too_high, no_view. The message says what to do."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


class TargetConfig(StrictModel):
    inner_corners: Annotated[list[Annotated[int, Field(ge=2, le=40)]], Field(min_length=2, max_length=2)]
    square_m: Annotated[float, Field(gt=0.0, lt=1.0)]
    margin_squares: Annotated[float, Field(ge=0.5, le=5.0)] = 1.0

    @property
    def pattern(self) -> tuple[int, int]:
        return int(self.inner_corners[0]), int(self.inner_corners[1])

    def object_points(self) -> np.ndarray:
        """(N, 3) float32 board-frame corners, row by row (OpenCV's order), z = 0."""
        cols, rows = self.pattern
        points = np.zeros((cols * rows, 3), np.float32)
        points[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * self.square_m
        return points


class CaptureLimits(StrictModel):
    min_views: Annotated[int, Field(ge=3, le=100)] = 10
    max_edge_width_px: Annotated[float, Field(gt=0.0, le=20.0)] = 3.5
    duplicate_px: Annotated[float, Field(ge=0.0, le=500.0)] = 20.0
    max_rms_px: Annotated[float, Field(gt=0.0, le=20.0)] = 1.0
    coverage_grid: Annotated[list[Annotated[int, Field(ge=1, le=32)]], Field(min_length=2, max_length=2)] = [8, 6]
    fix_aspect_ratio: bool = False


class IntrinsicsConfig(StrictModel):
    target: TargetConfig
    capture: CaptureLimits = CaptureLimits()


def load_intrinsics_config(path: str | Path | None = None) -> IntrinsicsConfig:
    return load_config(Path(path) if path is not None else config_dir() / "intrinsics.yaml", IntrinsicsConfig)


def grey_of(image: np.ndarray) -> np.ndarray:
    """(H, W) uint8 grey of a BGR or grey image."""
    if not isinstance(image, np.ndarray) or image.ndim not in (2, 3) or image.size == 0:
        raise IntrinsicsRejected("no_view", "no image to look at")
    return image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


MIN_IMAGE_SIDE_PX = 64  # smaller images hold no board worth calibrating from (and break the detectors' filters)
PRESENCE_SCALE = 0.5  # the board is first looked for at half size: an empty view is refused in a tenth of the time
CLASSIC_FLAGS = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE | cv2.CALIB_CB_FAST_CHECK  # findChessboardCorners


def board_in_view(grey: np.ndarray, pattern: tuple[int, int]) -> bool:
    """A quick look at half size for the board (both OpenCV detectors); False means no board worth measuring
    (one too small to find at half size is too small for calibration anyway). An empty 1280x720 view costs
    ~0.15 s here instead of ~0.6 s at full size, ten times that on a busy machine."""
    small = cv2.resize(grey, None, fx=PRESENCE_SCALE, fy=PRESENCE_SCALE, interpolation=cv2.INTER_AREA)
    found, _ = cv2.findChessboardCorners(small, pattern, CLASSIC_FLAGS)  # a few ms when the board is there
    if found:
        return True
    found, _ = cv2.findChessboardCornersSB(small, pattern, cv2.CALIB_CB_NORMALIZE_IMAGE)
    return bool(found)


def find_corners(grey: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """Inner corners (N, 2) float32 at sub-pixel accuracy, row by row; None if the board is not found.
    A quick look at half size first (board_in_view), then OpenCV's classic detector + cornerSubPix at
    full size (fast), the sector-based detector as a fallback."""
    if min(grey.shape) < MIN_IMAGE_SIDE_PX or not board_in_view(grey, pattern):
        return None
    found, corners = cv2.findChessboardCorners(grey, pattern, CLASSIC_FLAGS)
    if found:
        spacing = np.median(np.linalg.norm(np.diff(corners.reshape(-1, 2), axis=0), axis=1))
        window = int(np.clip(spacing * 0.4, 3, 15))
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 40, 1e-3)
        return cv2.cornerSubPix(grey, corners, (window, window), (-1, -1), criteria).reshape(-1, 2)
    found, corners = cv2.findChessboardCornersSB(grey, pattern, cv2.CALIB_CB_NORMALIZE_IMAGE)
    return corners.reshape(-1, 2).astype(np.float32) if found else None


def edge_width_px(grey: np.ndarray, pattern: tuple[int, int], corners: np.ndarray) -> float:
    """Blur of the board: the mean width (px) of its black-to-white edges (cv2.estimateChessboardSharpness;
    about 1-2 px when sharp, growing with blur, independent of the board's size in the image)."""
    sharpness = cv2.estimateChessboardSharpness(grey, pattern, corners.reshape(-1, 1, 2).astype(np.float32))
    return float(sharpness[0][0])  # (Scalar(mean edge width, min, max brightness), per-edge image)


def corner_distance_px(a: np.ndarray, b: np.ndarray) -> float:
    """Mean distance between two views' corners, the smaller of the two orderings (a board seen turned by
    180 degrees lists its corners in reverse)."""
    return float(min(np.linalg.norm(a - b, axis=1).mean(), np.linalg.norm(a - b[::-1], axis=1).mean()))


def covered_cells(corners: np.ndarray, image_size: tuple[int, int], grid: tuple[int, int]) -> np.ndarray:
    """(rows, cols) bool: the grid cells the board's outline (convex hull of its corners) overlaps."""
    width, height = image_size
    cols, rows = grid
    mask = np.zeros((rows * 16, cols * 16), np.uint8)  # 16x16 samples per cell
    scale = np.array([cols * 16 / width, rows * 16 / height])
    hull = cv2.convexHull(np.round(corners * scale).astype(np.int32))
    cv2.fillConvexPoly(mask, hull, 1)
    return mask.reshape(rows, 16, cols, 16).any(axis=(1, 3))


@dataclass
class CaptureView:
    corners_px: np.ndarray  # (N, 2)
    edge_width_px: float
    cells: np.ndarray  # (rows, cols) bool
    error_px: float | None = None  # per-view RMS after a solve

    def to_dict(self, index: int) -> dict:
        hull = cv2.convexHull(self.corners_px.astype(np.float32)).reshape(-1, 2)
        return {"index": index, "edge_width_px": round(self.edge_width_px, 3), "error_px": self.error_px,
                "outline_px": np.round(hull, 1).tolist()}


@dataclass
class IntrinsicsCapture:
    """Views kept so far for one camera image size. add() checks and keeps a view (or raises
    IntrinsicsRejected saying why); solve() calibrates from the kept views."""

    config: IntrinsicsConfig
    image_size: tuple[int, int]  # (width, height)
    views: list[CaptureView] = field(default_factory=list)

    def measure(self, image: np.ndarray) -> CaptureView:
        """The board's corners, sharpness and cells in one image (IntrinsicsRejected if none or blurry);
        reads only the config, so it may run outside whatever lock guards the kept views."""
        grey = grey_of(image)
        size = (grey.shape[1], grey.shape[0])
        if size != tuple(self.image_size):
            raise IntrinsicsRejected("size", f"the image is {size[0]}x{size[1]}, the capture is for {self.image_size[0]}x{self.image_size[1]}")
        pattern = self.config.target.pattern
        corners = find_corners(grey, pattern)
        if corners is None:
            raise IntrinsicsRejected("not_found", f"checkerboard not found: no {pattern[0]}x{pattern[1]} inner-corner board in view "
                                     "(the whole board with its white border must be in the image)")
        limits = self.config.capture
        width = edge_width_px(grey, pattern, corners)
        if not np.isfinite(width) or width > limits.max_edge_width_px:
            raise IntrinsicsRejected("blurry", f"too blurry: the board's edges are {width:.1f} px wide (at most "
                                     f"{limits.max_edge_width_px:g}): hold it still and in focus")
        return CaptureView(corners, width, covered_cells(corners, self.image_size, tuple(limits.coverage_grid)))

    def keep(self, view: CaptureView) -> CaptureView:
        """Keep a measured view unless it duplicates a kept one (IntrinsicsRejected); earlier errors are void."""
        limits = self.config.capture
        for index, kept in enumerate(self.views):
            distance = corner_distance_px(view.corners_px, kept.corners_px)
            if distance < limits.duplicate_px:
                raise IntrinsicsRejected("duplicate", f"duplicate of view {index}: the corners moved {distance:.1f} px on average "
                                         f"(at least {limits.duplicate_px:g}): move or tilt the board to a new place")
        self.views.append(view)
        for other in self.views:
            other.error_px = None  # an earlier solve no longer describes this set of views
        return view

    def add(self, image: np.ndarray) -> CaptureView:
        """measure() then keep(): check one image and keep its view."""
        return self.keep(self.measure(image))

    def delete(self, index: int) -> None:
        if not 0 <= index < len(self.views):
            raise IntrinsicsRejected("no_view", f"no view {index} (there are {len(self.views)})")
        del self.views[index]
        for other in self.views:
            other.error_px = None

    def coverage(self) -> np.ndarray:
        """(rows, cols) int: how many kept views reach each grid cell."""
        cols, rows = self.config.capture.coverage_grid
        counts = np.zeros((rows, cols), int)
        for view in self.views:
            counts += view.cells
        return counts

    def solve(self) -> IntrinsicCalibration:
        """K, distortion, RMS and per-view errors from the kept views (the views get their errors);
        IntrinsicsRejected when there are too few views or the RMS is above the limit."""
        limits = self.config.capture
        if len(self.views) < limits.min_views:
            raise IntrinsicsRejected("too_few_views", f"too few views: {len(self.views)} kept, {limits.min_views} needed "
                                     "(capture the board at more places and tilts)")
        calibration = solve_intrinsics([v.corners_px for v in self.views], self.config.target, self.image_size,
                                       limits.fix_aspect_ratio)
        for view, error in zip(self.views, calibration.per_view_errors):
            view.error_px = round(error, 4)
        if calibration.rms > limits.max_rms_px:
            worst = int(np.argmax(calibration.per_view_errors))
            raise IntrinsicsRejected("error_too_high", f"error too high: RMS {calibration.rms:.2f} px (at most {limits.max_rms_px:g}); "
                                     f"view {worst} is worst ({calibration.per_view_errors[worst]:.2f} px): delete it and capture again")
        return calibration

    def to_dict(self) -> dict:
        covered = self.coverage()
        return {"image_size": list(self.image_size), "views": [v.to_dict(i) for i, v in enumerate(self.views)],
                "coverage": covered.tolist(), "coverage_fraction": float((covered > 0).mean()),
                "min_views": self.config.capture.min_views, "grid": list(self.config.capture.coverage_grid),
                "target": {"inner_corners": list(self.config.target.pattern), "square_m": self.config.target.square_m}}


def solve_intrinsics(corners_px: list[np.ndarray], target: TargetConfig, image_size: tuple[int, int],
                     fix_aspect_ratio: bool = False) -> IntrinsicCalibration:
    """cv2.calibrateCamera over views' corners (each (N, 2), row by row): K, dist (k1 k2 p1 p2 k3), RMS px
    and each view's RMS reprojection error px."""
    objp = target.object_points()
    object_points = [objp] * len(corners_px)
    image_points = [np.asarray(c, np.float32).reshape(-1, 1, 2) for c in corners_px]
    flags = cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect_ratio else 0
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(object_points, image_points, tuple(image_size), None, None, flags=flags)
    per_view = []
    for img, rvec, tvec in zip(image_points, rvecs, tvecs):
        projected, _ = cv2.projectPoints(objp, rvec, tvec, K, dist)
        per_view.append(float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - img.reshape(-1, 2)) ** 2, axis=1)))))
    return IntrinsicCalibration(K=K, dist=dist.ravel(), rms=float(rms), per_view_errors=tuple(per_view),
                                image_size=tuple(image_size), views=tuple(f"view {i}" for i in range(len(corners_px))))
