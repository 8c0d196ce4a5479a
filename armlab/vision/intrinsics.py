"""Intrinsic calibration from checkerboard images (OpenCV's method: corners, sub-pixel refinement,
calibrateCamera), reporting the RMS reprojection error and one error per view."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.errors import InvalidInput


@dataclass(frozen=True)
class IntrinsicCalibration:
    """K (3x3), dist (k1, k2, p1, p2, k3), RMS reprojection error (px) and per-view RMS errors (px)."""

    K: np.ndarray
    dist: np.ndarray
    rms: float
    per_view_errors: tuple[float, ...]
    image_size: tuple[int, int]
    views: tuple[str, ...]

    def to_dict(self) -> dict:
        return {
            "K": self.K.tolist(),
            "dist": self.dist.ravel().tolist(),
            "rms": self.rms,
            "per_view_errors": list(self.per_view_errors),
            "image_size": list(self.image_size),
            "views": list(self.views),
        }

    def to_intrinsics(self) -> Intrinsics:
        return Intrinsics(
            width=self.image_size[0],
            height=self.image_size[1],
            fx=float(self.K[0, 0]),
            fy=float(self.K[1, 1]),
            cx=float(self.K[0, 2]),
            cy=float(self.K[1, 2]),
            dist=tuple(float(x) for x in self.dist.ravel()[:5]),
        )


def parse_pattern(text: str) -> tuple[int, int]:
    """'9x6' -> (9, 6) inner corners; ValueError otherwise."""
    try:
        cols, rows = (int(part) for part in text.lower().split("x"))
    except ValueError as error:
        raise InvalidInput(f"pattern must look like 9x6 (inner corners), got {text!r}") from error
    if cols < 2 or rows < 2:
        raise InvalidInput(f"pattern needs at least 2x2 inner corners, got {text!r}")
    return cols, rows


def find_chessboard(grey: np.ndarray, pattern: tuple[int, int], subpix_window: int = 11) -> np.ndarray | None:
    """Inner corners (N, 1, 2) float32 refined to sub-pixel, row by row; None if the board is not found."""
    found, corners = cv2.findChessboardCorners(grey, pattern, cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE)
    if not found:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 30, 1e-4)
    return cv2.cornerSubPix(grey, corners, (subpix_window, subpix_window), (-1, -1), criteria)


def calibrate_intrinsics(
    images: list[np.ndarray | str | Path],
    pattern: tuple[int, int] = (9, 6),
    square_m: float = 0.025,
    fix_aspect_ratio: bool = True,
    subpix_window: int = 11,
    min_views: int = 3,
) -> IntrinsicCalibration:
    """Calibrate from checkerboard views (arrays or paths). Views where the board is not found are
    skipped; ValueError if fewer than min_views remain, the images differ in size, or square_m <= 0."""
    if not (np.isfinite(square_m) and square_m > 0):
        raise InvalidInput(f"square size must be a positive number of metres, got {square_m}")
    cols, rows = pattern
    objp = np.zeros((cols * rows, 3), np.float32)
    objp[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square_m
    object_points, image_points, names = [], [], []
    size = None
    for index, item in enumerate(images):
        name = str(item) if isinstance(item, (str, Path)) else f"image[{index}]"
        image = cv2.imread(str(item), cv2.IMREAD_GRAYSCALE) if isinstance(item, (str, Path)) else item
        if image is None or not isinstance(image, np.ndarray) or image.size == 0:
            raise InvalidInput(f"{name}: cannot read the image")
        grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        if size is None:
            size = (grey.shape[1], grey.shape[0])
        elif size != (grey.shape[1], grey.shape[0]):
            raise InvalidInput(f"{name}: size {grey.shape[1]}x{grey.shape[0]} differs from the first image's {size[0]}x{size[1]}")
        corners = find_chessboard(grey, pattern, subpix_window)
        if corners is not None:
            object_points.append(objp)
            image_points.append(corners)
            names.append(name)
    if len(image_points) < min_views:
        raise InvalidInput(f"the {cols}x{rows} checkerboard was found in {len(image_points)} image(s); {min_views} are needed")
    flags = cv2.CALIB_FIX_ASPECT_RATIO if fix_aspect_ratio else 0
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(object_points, image_points, size, np.eye(3), None, flags=flags)
    per_view = []
    for obj, img, rvec, tvec in zip(object_points, image_points, rvecs, tvecs):
        projected, _ = cv2.projectPoints(obj, rvec, tvec, K, dist)
        per_view.append(float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - img.reshape(-1, 2)) ** 2, axis=1)))))
    return IntrinsicCalibration(K=K, dist=dist.ravel(), rms=float(rms), per_view_errors=tuple(per_view), image_size=size, views=tuple(names))
