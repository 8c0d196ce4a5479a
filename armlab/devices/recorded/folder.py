"""A folder of recorded RGB-D pairs: `image_<name>.png` (colour, 8-bit) + `depth_<name>.png` (16-bit mm,
aligned to colour: the same size), matched by <name>, sorted by it.

Every pair's PNG header (size, bit depth, channels) is checked when the folder is opened, so a wrong file
is refused at start-up naming it, without decoding every image; pixels are decoded when a pair is shown.
"""

from __future__ import annotations

import logging
import struct
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from armlab.devices.recorded.errors import RecordingError

__all__ = ["FramePair", "PngHeader", "RecordingError", "checked_pairs", "find_pairs", "png_header", "read_pair"]

log = logging.getLogger(__name__)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_COLOUR_TYPES = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}  # PNG colour type -> channels (3: palette, one index per pixel)


@dataclass(frozen=True)
class PngHeader:
    width: int
    height: int
    bit_depth: int
    channels: int
    palette: bool


def png_header(path: Path) -> PngHeader:
    """Size, bit depth and channels from a PNG's IHDR chunk (RecordingError if not a PNG)."""
    try:
        with path.open("rb") as file:
            head = file.read(33)
    except OSError as error:
        raise RecordingError(f"{path}: cannot read: {error}") from error
    if len(head) < 33 or head[:8] != PNG_SIGNATURE or head[12:16] != b"IHDR":
        raise RecordingError(f"{path}: not a PNG image")
    width, height, bit_depth, colour_type = struct.unpack(">IIBB", head[16:26])
    if colour_type not in _COLOUR_TYPES or width == 0 or height == 0:
        raise RecordingError(f"{path}: damaged PNG header (size {width}x{height}, colour type {colour_type})")
    return PngHeader(width, height, bit_depth, _COLOUR_TYPES[colour_type], colour_type == 3)


@dataclass(frozen=True)
class FramePair:
    """One recorded pair: its name (the shared suffix) and the two files."""

    name: str
    image_path: Path
    depth_path: Path


def check_pair(pair: FramePair) -> tuple[int, int]:
    """(width, height) of a pair whose colour is 8-bit and depth 16-bit single-channel of the same size."""
    color, depth = png_header(pair.image_path), png_header(pair.depth_path)
    if color.bit_depth != 8 or color.channels not in (1, 3, 4):
        raise RecordingError(f"{pair.image_path}: colour must be an 8-bit image, got {color.bit_depth}-bit with {color.channels} channels")
    if depth.bit_depth != 16 or depth.channels != 1 or depth.palette:
        raise RecordingError(
            f"{pair.depth_path}: depth must be single-channel 16-bit (millimetres), got {depth.bit_depth}-bit with {depth.channels} channel(s)"
        )
    if (depth.width, depth.height) != (color.width, color.height):
        raise RecordingError(
            f"{pair.depth_path}: depth is {depth.width}x{depth.height} but {pair.image_path.name} is {color.width}x{color.height}: "
            "depth must be aligned to colour (the same size)"
        )
    return color.width, color.height


def find_pairs(folder: Path) -> list[FramePair]:
    """The folder's pairs sorted by name; RecordingError if there are none (saying what was found)."""
    if not folder.is_dir():
        raise RecordingError(f"{folder}: no such folder")
    images = {p.name[len("image_"):-len(".png")]: p for p in folder.glob("image_*.png")}
    depths = {p.name[len("depth_"):-len(".png")]: p for p in folder.glob("depth_*.png")}
    names = sorted(images.keys() & depths.keys())
    if not names:
        raise RecordingError(
            f"{folder}: no recorded pairs: expected image_<name>.png with depth_<name>.png "
            f"(found {len(images)} image_*.png and {len(depths)} depth_*.png sharing no name)"
        )
    unpaired = sorted((images.keys() | depths.keys()) - set(names))
    if unpaired:
        log.warning("%s: skipping files without a partner: %s", folder, ", ".join(unpaired))
    return [FramePair(name, images[name], depths[name]) for name in names]


def checked_pairs(folder: Path, hold: str | None = None) -> tuple[list[FramePair], tuple[int, int]]:
    """The pairs to play (only `hold`'s when given) and their common (width, height), every header checked."""
    pairs = find_pairs(folder)
    if hold is not None:
        chosen = [pair for pair in pairs if pair.name == hold]
        if not chosen:
            raise RecordingError(f"{folder}: no pair named '{hold}' (pairs: {', '.join(p.name for p in pairs)})")
        pairs = chosen
    size = check_pair(pairs[0])
    for pair in pairs[1:]:
        other = check_pair(pair)
        if other != size:
            raise RecordingError(
                f"{pair.image_path}: {other[0]}x{other[1]}, but {pairs[0].image_path.name} is {size[0]}x{size[1]}: one camera, one size"
            )
    return pairs, size


def read_pair(pair: FramePair) -> tuple[np.ndarray, np.ndarray]:
    """(colour (H, W, 3) uint8 BGR, depth (H, W) uint16 mm), decoded; RecordingError naming a file that fails."""
    color = cv2.imread(str(pair.image_path), cv2.IMREAD_COLOR)
    if color is None:
        raise RecordingError(f"{pair.image_path}: cannot decode the colour image")
    depth = cv2.imread(str(pair.depth_path), cv2.IMREAD_ANYDEPTH)
    if depth is None or depth.dtype != np.uint16 or depth.ndim != 2:
        raise RecordingError(f"{pair.depth_path}: cannot decode as 16-bit depth")
    if depth.shape != color.shape[:2]:
        raise RecordingError(f"{pair.depth_path}: depth {depth.shape[::-1]} does not match the colour {color.shape[1::-1]}")
    return color, depth
