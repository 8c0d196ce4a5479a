"""The recorder's camera images at camera_scale, computed on the calling thread: the same pixels as cv2.resize.

cv2.resize splits its output into round(output pixels / 65536) stripes and, from two stripes on, hands them to
OpenCV's thread pool, whose worker then spins a while waiting for more work: for the recorder's 640x360 colour
frames at 30 fps that cost 2.3 % of one core on a thread no recorder figure named (bench/recording.py, 2026-12-05;
as much again as the resize itself). At a whole-number factor k (the default: camera_scale 0.5 of 1280x720) every
output row is computed from its own k input rows only, so:

- colour (INTER_AREA, each output pixel the mean of k x k input pixels, rounded) is resized in bands of at most
  STRIPE_PIXELS output pixels, each one stripe that OpenCV runs on the calling thread: the same pixels as one call;
- depth (INTER_NEAREST: OpenCV picks input pixel k * i) is every k-th pixel, a copy of a strided view.

Any other size or interpolation is one cv2.resize, as before. (Cheaper methods that are not the same pixels were
measured and not taken: INTER_LINEAR at exactly 0.5 is the same 2x2 mean at the same cost; cv2.pyrDown is a
Gaussian, not a mean, and 5x slower; a numpy 2x2 mean is 20x slower.)
"""

from __future__ import annotations

import cv2
import numpy as np

STRIPE_PIXELS = 65_536  # cv2.resize's stripe: a call with at most this many output pixels is one stripe


def scaled_size(width_px: int, height_px: int, scale: float) -> tuple[int, int]:
    """(width, height) of a width_px x height_px image at `scale`, at least 1 x 1 (as the recorder always sized it)."""
    return max(1, round(width_px * scale)), max(1, round(height_px * scale))


def whole_factor(shape: tuple[int, ...], size: tuple[int, int]) -> int | None:
    """k > 1 when an image of `shape` (rows, columns, ...) is `size` (width, height) times k in both directions."""
    height, width = shape[:2]
    k = width // size[0]
    return k if k > 1 and width == size[0] * k and height == size[1] * k else None


def scaled(image: np.ndarray, scale: float, interpolation: int) -> np.ndarray:
    """`image` at `scale` with cv2's `interpolation`, the same pixels as cv2.resize (a new C-contiguous array);
    scale >= 1: `image` itself."""
    if scale >= 1.0:
        return image
    size = scaled_size(image.shape[1], image.shape[0], scale)
    k = whole_factor(image.shape, size)
    if k is not None and interpolation == cv2.INTER_NEAREST:
        return np.ascontiguousarray(image[::k, ::k])
    if k is not None and interpolation == cv2.INTER_AREA:
        out = np.empty((size[1], size[0], *image.shape[2:]), dtype=image.dtype)
        band = max(1, STRIPE_PIXELS // size[0])  # output rows per call
        for row in range(0, size[1], band):
            end = min(size[1], row + band)
            cv2.resize(image[row * k: end * k], (size[0], end - row), dst=out[row:end], interpolation=cv2.INTER_AREA)
        return out
    return cv2.resize(image, size, interpolation=interpolation)
