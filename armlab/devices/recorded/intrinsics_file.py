"""Camera intrinsics from a file, for recorded RGB-D frames.

Layouts read (JSON or YAML; the first that matches wins):
- armlab's: `K` (3x3), `dist`, `image_size` [width, height] (what `armlab calibrate-intrinsics` prints and
  `armlab calibrate-extrinsics --intrinsics` reads);
- ROS camera_calibration_parsers YAML: `image_width`, `image_height`, `camera_matrix.data`, `distortion_coefficients.data`;
- a ROS CameraInfo dump: `k`/`K` (9 values), `d`/`D`, `width`, `height`;
- camera_info values kept beside recorded frames as `K_from_camera_info` + `D_from_camera_info_plumb_bob` (the
  ROB 550 development set's calibration file; its size is the frames').
Every error names the file and what is wrong with it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from armlab.config import read_config_file
from armlab.devices.camera import Intrinsics
from armlab.devices.recorded.errors import RecordingError
from armlab.errors import ConfigError


class IntrinsicsFileError(RecordingError):
    """An intrinsics file is missing, unreadable or holds no usable intrinsics (the message names it)."""


def _matrix(value, source: str, key: str) -> np.ndarray:
    try:
        K = np.asarray(value, dtype=float).reshape(3, 3)
    except (TypeError, ValueError) as error:
        raise IntrinsicsFileError(f"{source}: {key}: expected a 3x3 camera matrix ({error})") from error
    fx, fy, cx, cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
    if not (np.all(np.isfinite(K)) and fx > 0 and fy > 0 and cx > 0 and cy > 0):
        raise IntrinsicsFileError(f"{source}: {key}: fx, fy, cx, cy must be finite and > 0, got {fx}, {fy}, {cx}, {cy}")
    return K


def _dist(value, source: str, key: str) -> tuple[float, ...]:
    try:
        dist = tuple(float(x) for x in (value if value is not None else (0.0,) * 5))
    except (TypeError, ValueError) as error:
        raise IntrinsicsFileError(f"{source}: {key}: expected a list of distortion coefficients ({error})") from error
    if len(dist) not in (4, 5, 8, 12, 14) or not all(math.isfinite(x) for x in dist):
        raise IntrinsicsFileError(f"{source}: {key}: expected 4, 5, 8, 12 or 14 finite coefficients, got {list(dist)}")
    return dist


def _size(width, height, source: str, key: str) -> tuple[int, int]:
    try:
        size = (int(width), int(height))
    except (TypeError, ValueError) as error:
        raise IntrinsicsFileError(f"{source}: {key}: expected whole numbers ({error})") from error
    if size[0] <= 0 or size[1] <= 0:
        raise IntrinsicsFileError(f"{source}: {key}: the image size must be positive, got {size[0]}x{size[1]}")
    return size


def _layout(data: dict, source: str):
    """(K, dist, (width, height) or None, the keys used), or None when no known layout matches."""
    if "K" in data and ("image_size" in data or "width" in data):
        size = data.get("image_size")
        size = _size(*size, source, "image_size") if isinstance(size, (list, tuple)) and len(size) == 2 else (
            _size(data.get("width"), data.get("height"), source, "width/height") if size is None else None)
        if size is None:
            raise IntrinsicsFileError(f"{source}: image_size: expected [width, height], got {data.get('image_size')!r}")
        return _matrix(data["K"], source, "K"), _dist(data.get("dist", data.get("D")), source, "dist"), size, "K, dist, image_size"
    if "camera_matrix" in data and "image_width" in data:
        matrix = data["camera_matrix"]
        values = matrix.get("data") if isinstance(matrix, dict) else matrix
        coefficients = data.get("distortion_coefficients")
        coefficients = coefficients.get("data") if isinstance(coefficients, dict) else coefficients
        size = _size(data["image_width"], data.get("image_height"), source, "image_width/image_height")
        return _matrix(values, source, "camera_matrix"), _dist(coefficients, source, "distortion_coefficients"), size, "camera_matrix"
    for k_key, d_key in (("k", "d"), ("K", "D")):
        if k_key in data and "width" in data:
            size = _size(data["width"], data.get("height"), source, "width/height")
            return _matrix(data[k_key], source, k_key), _dist(data.get(d_key), source, d_key), size, f"{k_key}, {d_key}"
    if "K_from_camera_info" in data:
        dist = _dist(data.get("D_from_camera_info_plumb_bob"), source, "D_from_camera_info_plumb_bob")
        return _matrix(data["K_from_camera_info"], source, "K_from_camera_info"), dist, None, "K_from_camera_info, D_from_camera_info_plumb_bob"
    return None


def holds_intrinsics(path: Path) -> bool:
    """Whether `path` reads as a mapping with one of the known layouts (for finding a folder's intrinsics)."""
    try:
        data = read_config_file(path)
        return _layout(data, str(path)) is not None
    except (ConfigError, IntrinsicsFileError):
        return False


def read_intrinsics_file(path: str | Path, image_size: tuple[int, int] | None = None) -> tuple[Intrinsics, str]:
    """(Intrinsics, a one-line description of where they came from). `image_size` (width, height): the
    frames' size; a file that states another size is refused, one without a size takes it."""
    path = Path(path)
    source = str(path)
    if not path.is_file():
        raise IntrinsicsFileError(f"{source}: intrinsics file not found")
    try:
        data = read_config_file(path)
    except ConfigError as error:
        raise IntrinsicsFileError(f"{error} (expected intrinsics: K, dist, image_size)") from error
    found = _layout(data, source)
    if found is None:
        raise IntrinsicsFileError(
            f"{source}: no intrinsics: expected K (3x3), dist and image_size [width, height] "
            f"(or a ROS camera_info / camera_calibration YAML); keys found: {', '.join(sorted(map(str, data))) or 'none'}"
        )
    K, dist, size, keys = found
    if size is None:
        if image_size is None:
            raise IntrinsicsFileError(f"{source}: the file gives no image size and no frames were given to take it from")
        size = tuple(image_size)
    elif image_size is not None and tuple(size) != tuple(image_size):
        raise IntrinsicsFileError(
            f"{source}: intrinsics for {size[0]}x{size[1]} images, but the frames are {image_size[0]}x{image_size[1]}"
        )
    intrinsics = Intrinsics(int(size[0]), int(size[1]), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), dist)
    return intrinsics, f"{path.name} ({keys})"
