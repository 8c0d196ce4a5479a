"""Textures of the workcell, generated with OpenCV (no downloaded files): the board with its grid, the
calibration tags and optional ArUco tags for block tops (geometry and dictionaries: armlab.workcell).

Images are returned as RGB uint8 arrays laid out as seen from above: image row 0 is the +y (far) edge,
column 0 the -x edge, so a tag image is upright with its top edge toward +y (DESIGN §3)."""

from __future__ import annotations

import cv2
import numpy as np

from armlab.devices.sim.tag_bitmaps import tag_bitmap
from armlab.workcell.board import BoardSpec

BOARD_RGB = (150, 150, 146)
GRID_RGB = (70, 70, 70)
TAG_QUIET_CELLS = 2  # white quiet zone around each tag, in cells


def board_texture(board: BoardSpec, px_per_m: float = 2000.0, line_width_m: float = 0.0015) -> np.ndarray:
    """The board surface (the workcell's board rectangle) with a grid line through every grid point's x
    and y (DESIGN §3: lines at x = k * 50 mm, y = 25 mm + k * 50 mm), RGB, row 0 at +y."""
    (x0, x1), (y0, y1) = board.x_range_m, board.y_range_m
    width_px = int(round((x1 - x0) * px_per_m))
    height_px = int(round((y1 - y0) * px_per_m))
    image = np.empty((height_px, width_px, 3), dtype=np.uint8)
    image[:] = BOARD_RGB
    half_line_px = max(1, int(round(0.5 * line_width_m * px_per_m)))
    step = board.grid.step_m
    x_lines = np.arange(board.grid.x_m[0], board.grid.x_m[1] + 1e-9, step)
    y_lines = np.arange(board.grid.y_m[0], board.grid.y_m[1] + 1e-9, step)
    for x in x_lines:
        column = int(round((x - x0) * px_per_m))
        image[:, max(0, column - half_line_px) : column + half_line_px] = GRID_RGB
    for y in y_lines:
        row = int(round((y1 - y) * px_per_m))
        image[max(0, row - half_line_px) : row + half_line_px, :] = GRID_RGB
    return image


def tag_texture(tag_id: int, family: str = "DICT_APRILTAG_36h11", cell_px: int = 10,
                quiet_cells: int = TAG_QUIET_CELLS) -> tuple[np.ndarray, float]:
    """One tag of `family` (AprilTag family or OpenCV DICT_ name) with a white quiet zone reaching
    quiet_cells beyond the detected square (at least one cell beyond the printed bitmap), RGB,
    upright (the tag's top row first); and the texture's width in units of the detected square's side."""
    bitmap = tag_bitmap(family, tag_id)
    n = bitmap.cells.shape[0]
    pad = max(1, quiet_cells - (n - bitmap.edge_cells) // 2)
    image = cv2.resize(bitmap.cells, (n * cell_px, n * cell_px), interpolation=cv2.INTER_NEAREST)
    padded = cv2.copyMakeBorder(image, *(4 * [pad * cell_px]), cv2.BORDER_CONSTANT, value=255)
    return cv2.cvtColor(padded, cv2.COLOR_GRAY2RGB), (n + 2 * pad) / bitmap.edge_cells


def block_top_texture(aruco_id: int, color_rgb: tuple[int, int, int], edge_px: int = 60,
                      dictionary: int = cv2.aruco.DICT_4X4_250) -> np.ndarray:
    """A block's top face: an ArUco 4x4 tag (the workcell's block-tag dictionary) on a white square
    inside the block colour."""
    aruco_dict = cv2.aruco.getPredefinedDictionary(dictionary)
    cell = edge_px // 10
    marker = cv2.aruco.generateImageMarker(aruco_dict, int(aruco_id), 6 * cell, borderBits=1)
    white = cv2.copyMakeBorder(marker, cell, cell, cell, cell, cv2.BORDER_CONSTANT, value=255)
    face = np.empty((edge_px, edge_px, 3), dtype=np.uint8)
    face[:] = color_rgb
    start = (edge_px - white.shape[0]) // 2
    face[start : start + white.shape[0], start : start + white.shape[1]] = white[..., None]
    return face


def encode_png(image_rgb: np.ndarray) -> bytes:
    """PNG bytes of an RGB image (for MuJoCo's in-memory assets)."""
    ok, buffer = cv2.imencode(".png", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise RuntimeError("could not encode texture as PNG")
    return buffer.tobytes()
