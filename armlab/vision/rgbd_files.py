"""Colour and depth image files read and checked: a colour PNG/JPEG as BGR, an aligned depth PNG as
16-bit millimetres of the colour frame's size. ValueError naming the file when one is unusable."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np


def read_color(path: str | Path) -> np.ndarray:
    """A colour image (H, W, 3) uint8 BGR; ValueError naming the file if it is missing or not colour."""
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise ValueError(f"cannot read colour image {path}")
    if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
        raise ValueError(f"colour image {path} must be 8-bit BGR, got {image.dtype} with shape {image.shape}")
    return np.ascontiguousarray(image[..., :3])


def read_depth(path: str | Path, size_wh: tuple[int, int] | None = None) -> np.ndarray:
    """An aligned depth image (H, W) uint16 in mm (0 = no reading). size_wh: the colour frame's (width,
    height) it must match. ValueError naming the file on a wrong bit depth, channel count or size."""
    depth = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if depth is None:
        raise ValueError(f"cannot read depth image {path}")
    if depth.ndim != 2 or depth.dtype != np.uint16:
        bits = depth.dtype.itemsize * 8
        raise ValueError(f"depth image {path} must be single-channel 16-bit (mm), got {bits}-bit with shape {depth.shape}")
    if size_wh is not None and (depth.shape[1], depth.shape[0]) != tuple(size_wh):
        raise ValueError(f"depth image {path} is {depth.shape[1]}x{depth.shape[0]} but its colour frame is {size_wh[0]}x{size_wh[1]}")
    return depth
