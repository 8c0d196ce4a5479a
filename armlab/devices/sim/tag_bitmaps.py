"""Tag bitmaps for the simulated board, for any configured family: ArUco dictionaries and tag36h11 from
OpenCV's generator, tagStandard41h12 from the AprilTag project's published code words (data file
data/tagStandard41h12.yaml), laid out by the AprilTag library's own rule (apriltag_to_image)."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

_DATA_DIR = Path(__file__).with_name("data")
_OPENCV_ALIASES: dict[str, str] = {}


@dataclass(frozen=True)
class TagBitmap:
    """cells: (n, n) uint8 0/255, the whole printed tag (no quiet zone); edge_cells: the side, in cells,
    of the square whose corners a detector reports (what the board's tag size_m measures)."""

    cells: np.ndarray
    edge_cells: int


@functools.lru_cache(maxsize=4)
def _family_data(family: str) -> dict:
    path = _DATA_DIR / f"{family}.yaml"
    if not path.is_file():
        raise ValueError(f"no bitmap data for tag family '{family}' (have: tag36h11, tagStandard41h12, DICT_*)")
    return yaml.safe_load(path.read_text())


def tag_bitmap(family: str, tag_id: int) -> TagBitmap:
    """The bitmap of one tag of `family` (AprilTag family name or OpenCV DICT_* name)."""
    name = _OPENCV_ALIASES.get(family, family)
    if name.startswith("DICT_"):
        if not hasattr(cv2.aruco, name):
            raise ValueError(f"unknown OpenCV ArUco dictionary '{name}'")
        dictionary = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))
        edge = dictionary.markerSize + 2
        marker = cv2.aruco.generateImageMarker(dictionary, int(tag_id), edge, borderBits=1)
        return TagBitmap(cv2.copyMakeBorder(marker, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=255), edge)
    data = _family_data(name)
    codes = data["codes"]
    if not 0 <= tag_id < len(codes):
        raise ValueError(f"{name} has ids 0..{len(codes) - 1}, not {tag_id}")
    total, at_border, nbits = data["total_width"], data["width_at_border"], data["nbits"]
    image = np.zeros((total, total), dtype=np.uint8)
    white = at_border + (0 if data["reversed_border"] else 2)
    start = (total - white) // 2
    for i in range(white - 1):  # the one-cell white ring (apriltag_to_image)
        image[start, start + i] = 255
        image[start + i, total - 1 - start] = 255
        image[total - 1 - start, start + i + 1] = 255
        image[start + 1 + i, start] = 255
    border_start = (total - at_border) // 2
    code = int(codes[tag_id])
    for i, (x, y) in enumerate(zip(data["bit_x"], data["bit_y"])):
        if code & (1 << (nbits - i - 1)):
            image[y + border_start, x + border_start] = 255
    return TagBitmap(image, at_border)
