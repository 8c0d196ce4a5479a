"""Textures of the workcell, generated with OpenCV (no downloaded files): the board with its 50 mm grid,
the AprilTag 36h11 calibration tags and optional ArUco tags for block tops.

Images are returned as RGB uint8 arrays laid out as seen from above: image row 0 is the +y (far) edge,
column 0 the -x edge, so a tag image is upright with its top edge toward +y (DESIGN §3)."""

from __future__ import annotations

import cv2
import numpy as np

BOARD_SIZE_M = (1.0, 0.65)
BOARD_ORIGIN_M = (-0.5, -0.175)  # world (x, y) of the board's lower-left corner
GRID_PITCH_M = 0.05
GRID_X_OFFSET_M = 0.0  # vertical lines at x = k * 50 mm
GRID_Y_OFFSET_M = 0.025  # horizontal lines offset 25 mm from the origin

BOARD_RGB = (150, 150, 146)
GRID_RGB = (70, 70, 70)
TAG_CELLS = 8  # AprilTag 36h11: 6x6 data cells + a one-cell black border
TAG_QUIET_CELLS = 2  # white quiet zone around each tag, in cells


def board_texture(px_per_m: float = 2000.0, line_width_m: float = 0.0015) -> np.ndarray:
    """The board surface with its grid lines, RGB, row 0 at +y."""
    width_px = int(round(BOARD_SIZE_M[0] * px_per_m))
    height_px = int(round(BOARD_SIZE_M[1] * px_per_m))
    image = np.empty((height_px, width_px, 3), dtype=np.uint8)
    image[:] = BOARD_RGB
    half_line_px = max(1, int(round(0.5 * line_width_m * px_per_m)))
    x0, y0 = BOARD_ORIGIN_M
    x_lines = np.arange(-0.45, 0.45 + 1e-9, GRID_PITCH_M) + GRID_X_OFFSET_M
    # Horizontal lines at y = 25 mm + k * 50 mm: -175 ... 475 mm (the board's edges included).
    y_lines = np.arange(GRID_Y_OFFSET_M - 4 * GRID_PITCH_M, y0 + BOARD_SIZE_M[1] + 1e-9, GRID_PITCH_M)
    for x in x_lines:
        column = int(round((x - x0) * px_per_m))
        image[:, max(0, column - half_line_px) : column + half_line_px] = GRID_RGB
    for y in y_lines:
        row = int(round((y0 + BOARD_SIZE_M[1] - y) * px_per_m))
        image[max(0, row - half_line_px) : row + half_line_px, :] = GRID_RGB
    return image


def tag_texture(tag_id: int, dictionary: int = cv2.aruco.DICT_APRILTAG_36h11, cell_px: int = 10,
                cells: int = TAG_CELLS, quiet_cells: int = TAG_QUIET_CELLS) -> np.ndarray:
    """One tag with its white quiet zone, RGB, upright (the marker's top row first)."""
    aruco_dict = cv2.aruco.getPredefinedDictionary(dictionary)
    marker = cv2.aruco.generateImageMarker(aruco_dict, int(tag_id), cells * cell_px, borderBits=1)
    padded = cv2.copyMakeBorder(marker, *(4 * [quiet_cells * cell_px]), cv2.BORDER_CONSTANT, value=255)
    return cv2.cvtColor(padded, cv2.COLOR_GRAY2RGB)


def block_top_texture(aruco_id: int, color_rgb: tuple[int, int, int], edge_px: int = 60) -> np.ndarray:
    """A block's top face: an ArUco 4x4 tag (DICT_4X4_250) on a white square inside the block colour."""
    aruco_dict = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_250)
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
