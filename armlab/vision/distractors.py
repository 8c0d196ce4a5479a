"""Faces that are not cubes though block-coloured and flat: dark colourless parts (the arm's), and
patches on a larger colourless surface at their height. Magnitudes from the ROB 550 frames, as noted."""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np

from armlab.vision.block import Block
from armlab.vision.face_shape import Face, quantile

MIN_CHROMA = 0.15  # of the board's value: real cube tops 0.22-1.7, the dark arm's tinted parts 0.06-0.09 (ROB 550 frames)


def dark_and_colourless(face_hsv: np.ndarray, face_classes: np.ndarray, board_value: float) -> bool:
    """True when a face's block-coloured pixels are dark and grey (chroma = saturation x value), as the
    black arm's faintly tinted parts are: their median chroma is below MIN_CHROMA of the board's value."""
    coloured = face_classes > 0
    if not coloured.any():
        return False
    hsv = face_hsv.compress(coloured, axis=0).astype(np.float32)  # boolean indexing's rows, cheaper
    chroma = hsv[:, 1] * hsv[:, 2] / 255.0
    return quantile(chroma, 0.5) < MIN_CHROMA * board_value


def not_cube(block: Block) -> Block:
    return replace(block, is_cube=False) if block.is_cube else block


LARGER_SURFACE_RATIO = 1.5  # colourless surface at a face's height, connected to it, this many times its area: not a cube's top


def part_of_larger_surface(face: Face, z_small: np.ndarray, step: int, tol_m: float, coloured_small: np.ndarray | None) -> bool:
    """True when the face is a coloured patch on a larger surface at the same height (the dark arm's
    top with a coloured part, a hand, a box): the surface of heights within tol_m of the face that is
    connected to it holds LARGER_SURFACE_RATIO times the face's area or more of pixels that are not
    block-coloured (coloured_small: the frame's block-coloured pixels at `step`). A cube's top ends at
    its edges, where the height drops; touching cubes at the same height are block-coloured."""
    u, v = face.center_px / step
    r = max(4, int(3 * math.sqrt(face.pixel_count) / step))
    x0, y0 = max(0, int(u) - r), max(0, int(v) - r)
    window = z_small[y0 : int(v) + r + 1, x0 : int(u) + r + 1]
    if window.size == 0:
        return False
    band = (np.abs(window - face.top_m) < tol_m).astype(np.uint8)  # NaN and the robot's inf compare False, quietly
    n, labels = cv2.connectedComponents(band, connectivity=8)
    cu, cv_ = min(int(u) - x0, window.shape[1] - 1), min(int(v) - y0, window.shape[0] - 1)
    label = labels[cv_, cu]
    if label == 0:
        return False
    surface = labels == label
    if coloured_small is not None:
        surface &= ~coloured_small[y0 : y0 + window.shape[0], x0 : x0 + window.shape[1]].astype(bool)
    return np.count_nonzero(surface) * step * step >= LARGER_SURFACE_RATIO * face.pixel_count
