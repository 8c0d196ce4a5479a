"""Overlay drawing for the live stream (tags, detections with labels and yaw arrows, projected board
grid; each layer switchable) and the top-down board view through the board homography."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import cv2
import numpy as np

from armlab.errors import InvalidInput
from armlab.vision.blocks import Block
from armlab.vision.calibration import Calibration
from armlab.vision.geometry import PlaneCamera, project_points
from armlab.vision.tags import Tag, check_color_image
from armlab.workcell import load_workcell

# Drawing colours (BGR) per colour class; unknown names are drawn white.
DRAW_BGR = {
    "red": (40, 40, 230),
    "orange": (0, 140, 255),
    "yellow": (0, 230, 255),
    "green": (60, 200, 60),
    "blue": (230, 120, 30),
    "violet": (200, 60, 160),
}


@dataclass(frozen=True)
class OverlayLayers:
    """Which layers draw_overlay paints."""

    tags: bool = True
    detections: bool = True
    grid: bool = True
    labels: bool = True


def default_grid_points_m() -> np.ndarray:
    """The default workcell's board grid points (N, 3) at z = 0 (DESIGN §3: x -450..450, y -175..475 mm
    every 50 mm)."""
    return load_workcell().board.grid_points_m()


def draw_overlay(
    color_bgr: np.ndarray,
    tags: list[Tag] | None = None,
    blocks: list[Block] | None = None,
    calibration: Calibration | None = None,
    layers: OverlayLayers = OverlayLayers(),
    grid_points_m: np.ndarray | None = None,
    grid_px: np.ndarray | None = None,
    camera: PlaneCamera | None = None,
) -> np.ndarray:
    """A copy of the image with the enabled layers drawn; the input is never modified.

    grid_px: grid_pixels(calibration, grid_points_m, image size) when the caller keeps it per
    calibration (it changes only with the calibration); computed here when None. camera: the
    calibration's PlaneCamera, likewise (for the yaw arrows)."""
    check_color_image(color_bgr)
    out = color_bgr.copy() if color_bgr.ndim == 3 else cv2.cvtColor(color_bgr, cv2.COLOR_GRAY2BGR)
    if layers.grid and calibration is not None:
        if grid_px is None:
            grid_px = grid_pixels(calibration, grid_points_m, out.shape[:2])
        out.reshape(-1, 3)[grid_px] = (255, 255, 0)
    if layers.tags and tags:
        for tag in tags:
            corners = np.round(tag.corners_px).astype(np.int32)
            cv2.polylines(out, [corners], True, (0, 255, 0), 1, cv2.LINE_AA)
            cv2.circle(out, (int(corners[0, 0]), int(corners[0, 1])), 3, (0, 0, 255), -1)  # first corner marks orientation
            if layers.labels:
                u, v = np.round(tag.center_px).astype(int)
                cv2.putText(out, str(tag.id), (int(u) - 6, int(v) - 14), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 255, 0), 1, cv2.LINE_AA)
    if layers.detections and blocks:
        if camera is None and calibration is not None:
            camera = PlaneCamera(calibration.T_world_camera, calibration.K, calibration.dist)
        labels = [_draw_block(out, block, camera, layers.labels) for block in blocks]
        placed: list[tuple[int, int, int, int]] = []
        for label in labels:
            if label is not None:
                placed.append(_draw_label(out, *label, placed))
    return out


LABEL_SCALE = 0.6  # FONT_HERSHEY_SIMPLEX scale: ~13 px capitals at 1280 x 720, readable in the page's scaled view
LABEL_PAD_PX = 3


def place_label(
    anchor_px: tuple[int, int], size_px: tuple[int, int], placed: list[tuple[int, int, int, int]], image_wh: tuple[int, int]
) -> tuple[int, int, int, int]:
    """A label box (x, y, w, h) beside anchor_px (right-up first, then other sides, then further out) that
    overlaps no box in `placed` and stays inside the image when it can; the first candidate otherwise."""
    (u, v), (w, h) = anchor_px, size_px
    sides = [(10, -10 - h), (10, 10), (-10 - w, -10 - h), (-10 - w, 10), (-w // 2, -16 - h), (-w // 2, 16)]
    first = None
    for ring in range(6):
        for dx, dy in sides:
            x, y = u + dx, v + dy + (ring * (h + 2) if dy > 0 else -ring * (h + 2))
            box = (x, y, w, h)
            first = first or box
            inside = x >= 0 and y >= 0 and x + w <= image_wh[0] and y + h <= image_wh[1]
            if inside and not any(_boxes_overlap(box, other) for other in placed):
                return box
    return first


def _boxes_overlap(a: tuple[int, int, int, int], b: tuple[int, int, int, int]) -> bool:
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


_DIMMED = (np.arange(256) * 0.35).astype(np.uint8)  # a label's dark box: each 8-bit value times 0.35, truncated


@lru_cache(maxsize=512)
def _label_size(text: str) -> tuple[tuple[int, int], int]:
    """cv2.getTextSize of a label (the same few texts every frame: measured once each)."""
    return cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, LABEL_SCALE, 1)


def _draw_label(out: np.ndarray, text: str, anchor: tuple[int, int], colour, placed) -> tuple[int, int, int, int]:
    """Draw `text` on a dark box placed clear of the labels already drawn; returns its box."""
    (tw, th), baseline = _label_size(text)
    w, h = tw + 2 * LABEL_PAD_PX, th + baseline + 2 * LABEL_PAD_PX
    x, y, w, h = place_label(anchor, (w, h), placed, (out.shape[1], out.shape[0]))
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, out.shape[1]), min(y + h, out.shape[0])
    if x1 > x0 and y1 > y0:
        out[y0:y1, x0:x1] = cv2.LUT(out[y0:y1, x0:x1], _DIMMED)
    cv2.putText(out, text, (x + LABEL_PAD_PX, y + LABEL_PAD_PX + th), cv2.FONT_HERSHEY_SIMPLEX, LABEL_SCALE, colour, 1, cv2.LINE_AA)
    return (x, y, w, h)


def grid_pixels(cal: Calibration, grid_points_m: np.ndarray | None, image_hw: tuple[int, int]) -> np.ndarray:
    """Flat pixel indices (into an (H * W) image) of the 3x3 grid dots drawn by draw_overlay."""
    pts = grid_points_m if grid_points_m is not None else default_grid_points_m()
    px = np.round(project_points(cal.T_world_camera, cal.K, cal.dist, pts)).astype(int)
    h, w = image_hw
    px = px[(px[:, 0] >= 1) & (px[:, 0] < w - 1) & (px[:, 1] >= 1) & (px[:, 1] < h - 1)]
    offsets = np.array([dv * w + du for du in (-1, 0, 1) for dv in (-1, 0, 1)])  # 3x3 dots
    return ((px[:, 1] * w + px[:, 0])[:, None] + offsets[None, :]).ravel()


# A block's outline is drawn through the corners of its contour that matter: within this of every contour point
# (cv2.approxPolyDP). A face's contour is a pixel staircase of ~100 corners; each thick anti-aliased segment
# costs ~1 us to draw, and a fifth of them draw the same outline to the eye (a 2 px line, smoothed).
OUTLINE_TOLERANCE_PX = 0.75


def outline_px(contour_px: np.ndarray) -> np.ndarray:
    """(K, 1, 2) int32: the polygon the overlay draws for a contour (N, 2), within OUTLINE_TOLERANCE_PX of it."""
    return cv2.approxPolyDP(np.round(contour_px).astype(np.int32).reshape(-1, 1, 2), OUTLINE_TOLERANCE_PX, True)


def _draw_block(out: np.ndarray, block: Block, camera: PlaneCamera | None, labels: bool):
    """Outline, centre and yaw arrow of a block; returns its label (text, anchor px, colour) or None."""
    colour = DRAW_BGR.get(block.color, (255, 255, 255)) if block.is_cube else (160, 160, 160)
    cv2.drawContours(out, [outline_px(block.contour_px)], -1, colour, 2, cv2.LINE_AA)
    centre = tuple(int(round(x)) for x in block.center_px)
    cv2.circle(out, centre, 3, (255, 255, 255), -1)
    if camera is not None:
        half = 0.6 * block.side_m if block.side_m > 0 else 0.02
        tip_xy = block.position_m[:2] + half * np.array([math.cos(block.yaw_rad), math.sin(block.yaw_rad)])
        tip = camera.project(tip_xy, float(block.position_m[2]))[0]
        cv2.arrowedLine(out, centre, (int(round(tip[0])), int(round(tip[1]))), (255, 255, 255), 1, cv2.LINE_AA, tipLength=0.3)
    if labels:
        text = f"{block.color} {block.size}" if block.is_cube else f"not cube ({block.color})"
        if block.stack_level > 1:
            text += f" L{block.stack_level}"
        if block.aruco_id is not None:
            text += f" #{block.aruco_id}"
        if block.occluded:
            text += " (occluded)"
        return text, centre, tuple(min(255, c + 60) for c in colour)
    return None


def top_down_view(
    color_bgr: np.ndarray,
    cal: Calibration,
    mm_per_px: float = 1.0,
    x_range_m: tuple[float, float] | None = None,
    y_range_m: tuple[float, float] | None = None,
) -> np.ndarray:
    """The board seen from straight above (row 0 = +y edge, column 0 = -x edge), mm_per_px per pixel;
    ranges default to the workcell's board.

    Uses the board-plane homography, so only the board surface (z = 0) is geometrically exact.
    """
    if x_range_m is None or y_range_m is None:
        board = load_workcell().board
        x_range_m = board.x_range_m if x_range_m is None else x_range_m
        y_range_m = board.y_range_m if y_range_m is None else y_range_m
    check_color_image(color_bgr)
    if not (math.isfinite(mm_per_px) and mm_per_px > 0):
        raise InvalidInput(f"mm_per_px must be a positive number, got {mm_per_px}")
    s = mm_per_px / 1000.0
    width = int(round((x_range_m[1] - x_range_m[0]) / s))
    height = int(round((y_range_m[1] - y_range_m[0]) / s))
    if width * height > 16_000_000:
        raise InvalidInput(f"top-down view of {width}x{height} px is too large: raise mm_per_px")
    board_from_view = np.array([[s, 0, x_range_m[0] + s / 2], [0, -s, y_range_m[1] - s / 2], [0, 0, 1.0]])
    H = cal.H_image_board @ board_from_view
    src = color_bgr
    if np.any(cal.dist != 0):
        src = cv2.undistort(color_bgr, cal.K, cal.dist)
    return cv2.warpPerspective(src, H, (width, height), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP)
