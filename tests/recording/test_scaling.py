"""The recorder's image scaling (armlab/recording/scaling.py): the same pixels as one cv2.resize, each OpenCV call at
most one stripe (run on the calling thread, not OpenCV's pool)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from armlab.recording import scaling


def _colour(height: int, width: int, seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 256, (height, width, 3), dtype=np.uint8)


@pytest.mark.parametrize(("height", "width", "scale"), [(720, 1280, 0.5), (720, 1280, 0.25), (1080, 1920, 1 / 3), (480, 640, 0.5)])
def test_colour_equals_one_resize_and_the_block_mean(height: int, width: int, scale: float) -> None:
    image = _colour(height, width)
    result = scaling.scaled(image, scale, cv2.INTER_AREA)
    size = scaling.scaled_size(width, height, scale)
    assert result.shape == (size[1], size[0], 3) and result.dtype == np.uint8 and result.flags.c_contiguous
    assert np.array_equal(result, cv2.resize(image, size, interpolation=cv2.INTER_AREA))
    k = width // size[0]
    mean = image.reshape(size[1], k, size[0], k, 3).astype(float).mean(axis=(1, 3))
    assert np.abs(result - mean).max() <= 1.0  # the k x k mean, within one grey level


def test_depth_is_every_kth_reading_as_nearest() -> None:
    depth = np.random.default_rng(2).integers(0, 5000, (720, 1280), dtype=np.uint16)
    result = scaling.scaled(depth, 0.5, cv2.INTER_NEAREST)
    assert result.flags.c_contiguous and result.dtype == np.uint16
    assert np.array_equal(result, cv2.resize(depth, (640, 360), interpolation=cv2.INTER_NEAREST))


def test_other_sizes_are_one_resize_and_full_scale_is_the_image() -> None:
    image = _colour(720, 1280)
    assert np.array_equal(scaling.scaled(image, 0.6, cv2.INTER_AREA), cv2.resize(image, (768, 432), interpolation=cv2.INTER_AREA))
    assert scaling.scaled(image, 1.0, cv2.INTER_AREA) is image
    odd = _colour(721, 1281)  # not a whole factor
    assert np.array_equal(scaling.scaled(odd, 0.5, cv2.INTER_AREA), cv2.resize(odd, (640, 360), interpolation=cv2.INTER_AREA))


def test_every_opencv_call_is_one_stripe(monkeypatch: pytest.MonkeyPatch) -> None:
    """OpenCV runs a resize of at most STRIPE_PIXELS output pixels on the calling thread (its pool from two stripes)."""
    sizes = []
    resize = cv2.resize

    def recording_resize(image, size, *args, **kwargs):
        sizes.append(size)
        return resize(image, size, *args, **kwargs)

    monkeypatch.setattr(scaling.cv2, "resize", recording_resize)
    image = _colour(720, 1280)
    result = scaling.scaled(image, 0.5, cv2.INTER_AREA)
    assert len(sizes) > 1 and all(width * height <= scaling.STRIPE_PIXELS for width, height in sizes)
    assert sum(height for _, height in sizes) == 360
    monkeypatch.setattr(scaling.cv2, "resize", resize)
    assert np.array_equal(result, cv2.resize(image, (640, 360), interpolation=cv2.INTER_AREA))
