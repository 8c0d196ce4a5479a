"""Tags on block tops: whether a face looks tagged, and its id, colour and destination read from the
region around it at several scales (config block_tags)."""

from __future__ import annotations

from collections import Counter
from dataclasses import replace

import cv2
import numpy as np

from armlab.vision.block import Block
from armlab.vision.config import PerceptionConfig
from armlab.vision.distractors import MIN_CHROMA
from armlab.vision.tags import detect_tags


def face_looks_tagged(color_bgr: np.ndarray, block: Block, roi=None, roi_hsv: np.ndarray | None = None,
                       board_value: float | None = None) -> bool:
    """A top face whose middle is mostly colourless (white, grey or black: hue is noise on dark
    pixels, so they count too) may carry a tag. roi_hsv: the HSV image of the ROI, if at hand.
    board_value: the board's median value in this frame; given, colourless = chroma (S x V) below
    MIN_CHROMA of it (a dark real violet top is dim but coloured), else S or V below 60."""
    u, v = block.center_px.astype(int).tolist()
    xa, ya, xb, yb = max(0, u - 4), max(0, v - 4), u + 5, v + 5
    if roi_hsv is not None and roi[0] <= xa and roi[1] <= ya and xb <= roi[2] and yb <= roi[3]:
        hsv = roi_hsv[ya - roi[1] : yb - roi[1], xa - roi[0] : xb - roi[0]]
    else:
        patch = color_bgr[ya:yb, xa:xb]
        if patch.size == 0:
            return False
        hsv = cv2.cvtColor(patch, cv2.COLOR_BGR2HSV)
    if board_value is not None:
        chroma = hsv[..., 1].astype(np.float32) * hsv[..., 2] / 255.0
        return np.count_nonzero(chroma < MIN_CHROMA * board_value) / chroma.size > 0.5  # the fraction np.mean gives
    return np.count_nonzero((hsv[..., 1] < 60) | (hsv[..., 2] < 60)) / hsv[..., 1].size > 0.5


TAG_RETRY_SCALES = (3.0, 4.0, 1.0)  # when the 2x read finds no tag on a face: a tag of ~2 px per bit reads at some scales only


def tag_ids_on(block: Block, color_bgr: np.ndarray, roi, detector, scale: float) -> list[int]:
    """Ids of the tags whose centre lies on the block's face, read from the ROI resized by `scale`."""
    x0, y0, x1, y1 = roi
    crop = color_bgr[y0:y1, x0:x1]
    if scale != 1.0:
        crop = cv2.resize(crop, None, fx=scale, fy=scale, interpolation=cv2.INTER_CUBIC)
    if min(crop.shape[:2]) < 16:
        return []
    reach_px = 0.5 * np.ptp(block.contour_px, axis=0).max()
    return [tag.id for tag in detect_tags(crop, detector=detector)
            if np.linalg.norm(tag.center_px / scale + np.array([x0, y0]) - block.center_px) < reach_px]


def with_tag(block: Block, color_bgr: np.ndarray, roi, detector, cfg: PerceptionConfig) -> Block:
    """The block with its top tag's id, colour and destination (config), if a tag is found on it: read
    from the ROI at 2x; if that finds none, at TAG_RETRY_SCALES, where an id counts when it is one of the
    configured block tags or read at two scales (a tiny tag misreads now and then, never the same way).
    A tag read at no scale (a small block's tag seen askew from far, under 2 px per bit) leaves aruco_id None;
    when exactly one configured block tag has the block's colour (the id <-> colour table of block_tags),
    the block gets that tag's destination."""
    ids = tag_ids_on(block, color_bgr, roi, detector, 2.0)[:1]
    if not ids:
        reads = [tag_id for scale in TAG_RETRY_SCALES for tag_id in tag_ids_on(block, color_bgr, roi, detector, scale)]
        counts = Counter(reads)
        ids = sorted((tag_id for tag_id, n in counts.items() if tag_id in cfg.tags.block_tags or n >= 2),
                     key=lambda tag_id: (-counts[tag_id], tag_id not in cfg.tags.block_tags))[:1]
    if not ids:
        by_colour = [entry for entry in cfg.tags.block_tags.values() if entry.color == block.color]
        return replace(block, destination=by_colour[0].destination) if len(by_colour) == 1 else block
    entry = cfg.tags.block_tags.get(ids[0])
    return replace(block, aruco_id=ids[0], color=entry.color if entry else block.color,
                   destination=entry.destination if entry else None)
