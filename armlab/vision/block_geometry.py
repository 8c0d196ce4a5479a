"""What block detection needs from a calibration, computed once (BlockGeometry: the plane mapper, the
board-plane fitter's terms, the height terms), re-based on the board plane fitted in a frame
(frame_geometry), and the world heights of a region of interest (roi_heights). Shared by blocks.py
and face_shape.py."""

from __future__ import annotations

import copy

import cv2
import numpy as np

from armlab.vision.board_plane import BoardPlane, BoardPlaneError, BoardPlaneFitter
from armlab.vision.calibration import Calibration
from armlab.vision.colors import board_region_mask
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import PlaneCamera, height_coefficients

STEP = 4  # candidates at quarter resolution (a small cube's top is still ~6x6 px); measured at full


class BlockGeometry:
    """What detect_blocks needs from a calibration, computed once: the plane mapper, the board-plane
    fitter's per-pixel terms and, for heights above a plane (row = (n, D): height = n . X + D for depth
    camera points X), the terms of the quarter-resolution height map and, per full-resolution column
    and row, of a pixel's height. Built for the calibration's depth model (T_world_depth); with_heights
    gives the same for the board plane fitted in a frame. Read-only once built."""

    def __init__(self, cal: Calibration, cfg: PerceptionConfig | None = None) -> None:
        K = cal.K
        self.calibration = cal
        self.camera = PlaneCamera(cal.T_world_camera, K, cal.dist)
        self.small_shape = (-(-cal.height // STEP), -(-cal.width // STEP))  # of image[::STEP, ::STEP]
        self.small_K = K / np.array([[STEP], [STEP], [1]])
        self.fitter = None
        if cfg is not None and cfg.board_plane.enabled:
            self.fitter = BoardPlaneFitter(K, cal.dist, cal.T_world_depth, cal.width, cal.height,
                                           cfg.board.x_range_m, cfg.board.y_range_m, step=2 * STEP)
        self._set_heights(cal.T_world_depth[2])
        self.plane: BoardPlane | None = None  # the frame's board plane, when with_heights made this
        self._board_regions: dict = {}  # board_region's masks, shared with with_heights' copies (same calibration)

    def board_region(self, x_range_m, y_range_m) -> np.ndarray:
        """colors.board_region_mask at STEP for this calibration, computed once per board rectangle (read-only)."""
        key = (tuple(x_range_m), tuple(y_range_m))
        mask = self._board_regions.get(key)
        if mask is None:
            cal = self.calibration
            mask = board_region_mask(self.small_shape, cal.T_world_camera, cal.K, cal.dist, x_range_m, y_range_m, STEP)
            mask.flags.writeable = False
            self._board_regions[key] = mask
        return mask

    def _set_heights(self, row: np.ndarray) -> None:
        K, cal = self.calibration.K, self.calibration
        T = np.eye(4)
        T[2] = row
        self.small_coefficients = height_coefficients(self.small_shape, self.small_K, T)
        r3 = np.asarray(row[:3], dtype=np.float32)
        self.height_row = T
        self.height_u = r3[0] * ((np.arange(cal.width, dtype=np.float32) - K[0, 2]) / K[0, 0])
        self.height_v = r3[1] * ((np.arange(cal.height, dtype=np.float32) - K[1, 2]) / K[1, 1])
        self.height_1 = r3[2]
        self.height_t = np.float32(row[3])

    def with_heights(self, plane: BoardPlane) -> BlockGeometry:
        """A copy measuring heights from `plane` (a board plane fitted in the depth camera's frame)."""
        other = copy.copy(self)
        other._set_heights(plane.height_row())
        other.plane = plane
        return other


def frame_geometry(geo: BlockGeometry, depth_m_small: np.ndarray, cfg: PerceptionConfig,
                   exclude_small: np.ndarray | None = None) -> BlockGeometry:
    """geo measuring heights from the board plane fitted in this frame's depth (quarter resolution, in
    metres), so heights follow the depth camera's own board; geo itself (the calibration's depth model)
    when the fit is disabled or finds no dominant board plane (the board hidden, no depth)."""
    if geo.fitter is None:
        return geo
    bp = cfg.board_plane
    try:
        # Every 2nd quarter-resolution pixel (~14 000): the plane's 3 numbers are fixed many times over.
        plane = geo.fitter.fit(depth_m_small[::2, ::2], bp.window_m, bp.inlier_m,
                               None if exclude_small is None else exclude_small[::2, ::2], bp.min_inlier_fraction)
    except BoardPlaneError:
        return geo
    return geo.with_heights(plane)


def roi_heights(depth_mm: np.ndarray, geo: BlockGeometry, roi: tuple[int, int, int, int]) -> np.ndarray:
    """World z (m) of a region of interest from 3x3-median-filtered depth (edges kept, noise about halved)."""
    x0, y0, x1, y1 = roi
    d = cv2.medianBlur(depth_mm[y0:y1, x0:x1], 3).astype(np.float32)
    d /= 1000.0
    # The same sums and products as d * (u + v + 1) + t, in place.
    z = np.add(geo.height_u[None, x0:x1], geo.height_v[y0:y1, None])
    z += geo.height_1
    z *= d
    z += geo.height_t
    np.copyto(z, np.nan, where=d <= 0)
    return z
