"""Pixel and mask helpers of block detection (blocks.py): the hue classes of an HSV image, connected
components and blobs of masks, a mask's pixels, pixel gathers, and whether a region holds ignored
(robot) pixels. Pure functions of their arrays, written for the per-frame cost (issue 17): each gives
what the direct numpy formulation gives (tests/vision/test_perception_speedups.py)."""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from armlab.vision.config import PerceptionConfig


def hue_lut(cfg: PerceptionConfig) -> tuple[np.ndarray, list[str]]:
    """Lookup table hue (0..179) -> index of the nearest configured colour (cyclic hue distance)."""
    names = list(cfg.blocks.colors)
    return _hue_lut(tuple(cfg.blocks.colors[n] for n in names)).copy(), names


@lru_cache(maxsize=16)
def _hue_lut(centres_deg: tuple[float, ...]) -> np.ndarray:
    hues = np.arange(180)[:, None]
    diff = np.abs(hues - np.array(centres_deg)[None, :])
    diff = np.minimum(diff, 180 - diff)
    return np.argmin(diff, axis=1).astype(np.uint8)


def class_table(lut: np.ndarray) -> np.ndarray:
    """hue_lut's table as cv2.LUT wants it: 256 entries of colour index + 1."""
    table = np.empty(256, np.uint8)
    table[:180] = lut + 1
    table[180:] = table[179]
    return table


@lru_cache(maxsize=16)
def frozen_class_table(centres_deg: tuple[float, ...]) -> np.ndarray:
    """_class_table of these colour centres, built once (read-only)."""
    table = class_table(_hue_lut(centres_deg))
    table.flags.writeable = False
    return table


def colour_classes(hsv: np.ndarray, cfg: PerceptionConfig, table: np.ndarray) -> np.ndarray:
    """Per-pixel colour index + 1 (0 = not a block colour: grey, dark or washed out).

    Two OpenCV passes: the _class_table on the hue plane (hues past 179 count as 179), and a range
    mask for enough saturation and value."""
    classes = cv2.LUT(cv2.extractChannel(hsv, 0), table)
    colourful = cv2.inRange(hsv, (0, cfg.blocks.min_saturation, cfg.blocks.min_value), (255, 255, 255))
    return cv2.bitwise_and(classes, colourful)


NEAR_COLOUR_KERNEL = np.ones((7, 7), np.uint8)  # a tag's white within 3 quarter-resolution pixels of block colour


def components(mask: np.ndarray) -> tuple[int, np.ndarray, list[list[int]]]:
    """8-connected components of a uint8 mask: (count with the background, labels over the window of the
    mask's set pixels, each label's [x, y, width, height, area] in image coordinates; the first row is the
    window's x, y). Grana's block-based labelling: the default's (Spaghetti's) labels here, about 3x faster;
    on the window only (its corner on even rows and columns, as the labelling's 2x2 blocks lie in the image,
    so the labels are numbered as over the whole image): the stats cost time per pixel."""
    x, y, w, h = cv2.boundingRect(mask)
    if w == 0 or h == 0:  # nothing set: the background alone
        return 1, np.zeros((0, 0), np.int32), [[0, 0, 0, 0, 0]]
    x0, y0 = x - x % 2, y - y % 2
    n, labels, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(mask[y0 : y + h, x0 : x + w], 8, cv2.CV_32S, cv2.CCL_GRANA)
    stats[:, 0] += x0
    stats[:, 1] += y0
    stats[0, :2] = (x0, y0)
    return n, labels, stats.tolist()  # plain ints: cheaper arithmetic and slicing than numpy scalars


def largest_blob(mask: np.ndarray) -> np.ndarray | None:
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=4)
    if n <= 1:
        return None
    return (labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))).view(np.uint8)


def seeded_blob(mask: np.ndarray, seed: np.ndarray | None) -> np.ndarray | None:
    """The connected part of mask holding most seed pixels (the largest when no seed pixel is in it)."""
    if seed is None:
        return largest_blob(mask)
    n, labels = cv2.connectedComponents(mask.view(np.uint8), connectivity=4)
    if n <= 1:
        return None
    hits = np.bincount(labels[seed & mask.view(bool)], minlength=n)
    if hits[1:].max() == 0:
        return largest_blob(mask)
    return (labels == 1 + int(np.argmax(hits[1:]))).view(np.uint8)


def pixels_of(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(flat indices, rows, columns) of a 2-D mask's set pixels in row-major order: np.nonzero's rows and
    columns, from flat indices (which gather with np.take far cheaper than row/column pairs index)."""
    flat = np.flatnonzero(mask)
    ys, xs = np.divmod(flat, mask.shape[1])
    return flat, ys, xs


def any_ignored(ignore_mask: np.ndarray, ignore_cells: tuple[np.ndarray, int] | None, roi) -> bool:
    """Whether the ROI holds ignored pixels: on the cells ignore_mask upscales, if given (the cells its pixels fall in)."""
    x0, y0, x1, y1 = roi
    if ignore_cells is None:
        return bool(ignore_mask[y0:y1, x0:x1].any())
    cells, s = ignore_cells
    return bool(cells[y0 // s : (y1 - 1) // s + 1, x0 // s : (x1 - 1) // s + 1].any())


def pixels_at(color_bgr: np.ndarray, px: np.ndarray) -> np.ndarray:
    """color_bgr[px[:, 1], px[:, 0]] (px: (N, 2) integer columns and rows), by one np.take of flat indices."""
    if not color_bgr.flags.c_contiguous:
        return color_bgr[px[:, 1], px[:, 0]]
    return color_bgr.reshape(-1, color_bgr.shape[2]).take(px[:, 1] * color_bgr.shape[1] + px[:, 0], axis=0)
