"""Block detection from colour + depth: colour class, size class from the metric footprint, top-face
centre and yaw in the world, stack level from height, touching same-colour blocks split, arm
occlusion flagged, distractors rejected, and tag-topped blocks identified.

Speed: colour and height are computed at half resolution to find candidates; each candidate's top
face is then measured on a full-resolution region of interest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

from armlab.vision.calibration import Calibration
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import height_map_m, intersect_rays_with_plane, normalized_rays, project_points
from armlab.vision.tags import check_color_image, detect_tags, make_detector

MIN_FILL = 0.84  # top-face area / its minimum-area rectangle: squares ~0.95, discs 0.785
MAX_ASPECT = 1.3
SIZE_TOLERANCE = 0.22  # measured side within this fraction of the class size
HEIGHT_TOLERANCE_M = 0.0045  # top height vs a sum of cube edges


@dataclass(frozen=True)
class Block:
    """A detected block (the top one of a stack); positions in world metres, yaw mod pi/2 in [-pi/4, pi/4)."""

    color: str
    size: str
    position_m: np.ndarray
    yaw_rad: float
    height_m: float
    stack_level: int
    center_px: np.ndarray
    contour_px: np.ndarray
    is_cube: bool = True
    occluded: bool = False
    aruco_id: int | None = None
    destination: int | None = None
    side_m: float = 0.0
    stack_sizes: tuple[str, ...] = field(default=())

    def to_dict(self) -> dict:
        return {
            "color": self.color,
            "size": self.size,
            "position_m": [float(x) for x in self.position_m],
            "yaw_rad": float(self.yaw_rad),
            "height_m": float(self.height_m),
            "stack_level": int(self.stack_level),
            "stack_sizes": list(self.stack_sizes),
            "center_px": [float(x) for x in self.center_px],
            "is_cube": bool(self.is_cube),
            "occluded": bool(self.occluded),
            "aruco_id": self.aruco_id,
            "destination": self.destination,
            "side_m": float(self.side_m),
        }


def hue_lut(cfg: PerceptionConfig) -> tuple[np.ndarray, list[str]]:
    """Lookup table hue (0..179) -> index of the nearest configured colour (cyclic hue distance)."""
    names = list(cfg.blocks.colors)
    centres = np.array([cfg.blocks.colors[n] for n in names])
    hues = np.arange(180)[:, None]
    diff = np.abs(hues - centres[None, :])
    diff = np.minimum(diff, 180 - diff)
    return np.argmin(diff, axis=1).astype(np.uint8), names


def color_classes(hsv: np.ndarray, cfg: PerceptionConfig, lut: np.ndarray) -> np.ndarray:
    """Per-pixel colour index + 1 (0 = not a block colour: grey, dark or washed out)."""
    h, s, v = hsv[..., 0], hsv[..., 1], hsv[..., 2]
    classes = lut[np.minimum(h, 179)] + 1
    classes[(s < cfg.blocks.min_saturation) | (v < cfg.blocks.min_value)] = 0
    return classes


def stack_from_height(top_m: float, top_size: str, cfg: PerceptionConfig) -> tuple[int, tuple[str, ...], float]:
    """(stack level, sizes bottom..top, height mismatch m) for a top face at top_m with the given top block.

    Piles hold large blocks below small ones, so the blocks under a large block are large.
    """
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    top_edge = large if top_size == "large" else small
    below = top_m - top_edge
    best = (1, (top_size,), abs(below))
    for n_large in range(0, 12):
        for n_small in range(0, 12 if top_size == "small" else 1):
            err = abs(below - n_large * large - n_small * small)
            if err < best[2] - 1e-9:
                best = (1 + n_large + n_small, ("large",) * n_large + ("small",) * n_small + (top_size,), err)
    return best


@dataclass
class _Face:
    """A measured flat top face before classification."""

    points_xy: np.ndarray  # (N, 2) world
    top_m: float
    contour_px: np.ndarray
    center_px: np.ndarray
    pixel_count: int
    pixel_area_m2: float


def _measure_rect(points_xy: np.ndarray, pitch_m: float) -> tuple[np.ndarray, float, float, float, float]:
    """(centre xy, side_a, side_b, yaw mod pi/2 in [-pi/4, pi/4), fill) of a point set's minimum rectangle."""
    (cx, cy), (wa, wb), angle_deg = cv2.minAreaRect(points_xy.astype(np.float32))
    wa, wb = wa + pitch_m, wb + pitch_m  # pixel centres sit half a pixel inside the edges
    yaw = math.radians(angle_deg)
    yaw = (yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4
    fill = points_xy.shape[0] * pitch_m * pitch_m / max(wa * wb, 1e-12)
    return np.array([cx, cy]), wa, wb, yaw, fill


def _classify_face(face: _Face, cfg: PerceptionConfig) -> tuple[str, float, float, bool, np.ndarray]:
    """(size, side_m, yaw, is_cube, centre_xy) from the face's metric footprint and height."""
    pitch = math.sqrt(face.pixel_area_m2)
    centre, wa, wb, yaw, fill = _measure_rect(face.points_xy, pitch)
    side = math.sqrt(wa * wb)
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    size = "large" if abs(side - large) < abs(side - small) else "small"
    edge = large if size == "large" else small
    _, _, height_err = stack_from_height(face.top_m, size, cfg)
    is_cube = (
        fill >= MIN_FILL
        and max(wa, wb) / max(min(wa, wb), 1e-9) <= MAX_ASPECT
        and abs(side - edge) <= SIZE_TOLERANCE * edge
        and height_err <= HEIGHT_TOLERANCE_M
    )
    centroid = face.points_xy.mean(axis=0)
    return size, side, yaw, is_cube, (centroid if is_cube else centre)


def _split_touching(face: _Face, cfg: PerceptionConfig) -> list[_Face]:
    """Split a face holding several touching same-colour cubes by k-means on its points; [face] if no split fits."""
    area = face.pixel_count * face.pixel_area_m2
    candidates = []
    for edge in (cfg.blocks.large_size_m, cfg.blocks.small_size_m):
        n = int(round(area / (edge * edge)))
        if 2 <= n <= 6:
            candidates.append(n)
    for n in candidates:
        pts = face.points_xy.astype(np.float32)
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-5)
        _, labels, _ = cv2.kmeans(pts, n, None, criteria, 4, cv2.KMEANS_PP_CENTERS)
        parts = []
        for k in range(n):
            sel = labels.ravel() == k
            parts.append(_Face(face.points_xy[sel], face.top_m, face.contour_px, face.center_px, int(sel.sum()), face.pixel_area_m2))
        if all(_classify_face(p, cfg)[3] for p in parts):
            return parts
    return [face]


def _roi_heights(depth_mm: np.ndarray, cal: Calibration, roi: tuple[int, int, int, int]) -> np.ndarray:
    """World z (m) of a region of interest from 5x5-median-filtered depth (edges kept, noise ~4x lower)."""
    x0, y0, x1, y1 = roi
    d = cv2.medianBlur(np.ascontiguousarray(depth_mm[y0:y1, x0:x1]), 5).astype(np.float32) / 1000.0
    K = cal.K
    us = (np.arange(x0, x1, dtype=np.float32) - K[0, 2]) / K[0, 0]
    vs = (np.arange(y0, y1, dtype=np.float32) - K[1, 2]) / K[1, 1]
    r3 = cal.T_world_camera[2, :3].astype(np.float32)
    z = d * (r3[0] * us[None, :] + r3[1] * vs[:, None] + r3[2]) + np.float32(cal.T_world_camera[2, 3])
    z[d <= 0] = np.nan
    return z


def _largest_blob(mask: np.ndarray) -> np.ndarray | None:
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=4)
    if n <= 1:
        return None
    return (labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))).astype(np.uint8)


def _top_face_in_roi(
    z: np.ndarray, roi: tuple[int, int, int, int], top_m: float, keep: np.ndarray | None, tol_m: float
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Full-res pixels (N, 2), contour and median height of the flat face near top_m in the ROI's heights z.

    Two passes: a loose band around the guess finds the face, a tight band around its median keeps
    only the face (side-face pixels just below the top edge would bias the footprint toward the camera).
    """
    x0, y0 = roi[0], roi[1]
    with np.errstate(invalid="ignore"):
        blob = _largest_blob((np.abs(z - top_m) < tol_m) & (keep if keep is not None else True))
        if blob is None:
            return None
        face_m = float(np.nanmedian(z[blob > 0]))
        blob = _largest_blob((np.abs(z - face_m) < 0.5 * tol_m) & (keep if keep is not None else True))
    if blob is None:
        return None
    contours, _ = cv2.findContours(blob, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    ys, xs = np.nonzero(blob)
    pixels = np.stack([xs + x0, ys + y0], axis=1).astype(np.float64)
    contour = max(contours, key=cv2.contourArea).reshape(-1, 2) + np.array([x0, y0])
    return pixels, contour, float(np.nanmedian(z[ys, xs]))


def _face_from_pixels(pixels: np.ndarray, contour: np.ndarray, top_m: float, cal: Calibration) -> _Face:
    rays = normalized_rays(pixels, cal.K, cal.dist)
    world = intersect_rays_with_plane(cal.T_world_camera, rays, top_m)
    centre = world[:, :2].mean(axis=0)
    depth_m = float(np.linalg.norm(cal.T_world_camera[:3, 3] - np.array([centre[0], centre[1], top_m])))
    cos_view = abs(float(cal.T_world_camera[2, 2]))  # camera z-axis vs world z: foreshortening of the face
    pixel_area = (depth_m / cal.K[0, 0]) * (depth_m / cal.K[1, 1]) * cos_view
    return _Face(world[:, :2], top_m, contour.astype(np.float64), pixels.mean(axis=0), pixels.shape[0], pixel_area)


def detect_blocks(
    color_bgr: np.ndarray,
    depth_mm: np.ndarray,
    cal: Calibration,
    cfg: PerceptionConfig,
    tag_detector: cv2.aruco.ArucoDetector | None = None,
) -> list[Block]:
    """Blocks (top of each stack) and flagged non-cubes on the board, sorted by y then x.

    tag_detector: a prebuilt detector for the block-tag dictionary (saves its construction per frame).
    """
    check_color_image(color_bgr)
    if color_bgr.ndim != 3:
        raise ValueError("detect_blocks needs a BGR colour image")
    h, w = color_bgr.shape[:2]
    if (w, h) != (cal.width, cal.height):
        raise ValueError(f"image is {w}x{h} but the calibration is for {cal.width}x{cal.height}")
    if not isinstance(depth_mm, np.ndarray) or depth_mm.shape != (h, w) or depth_mm.dtype != np.uint16:
        raise ValueError(f"depth must be a uint16 (H, W) = ({h}, {w}) image in mm, got {getattr(depth_mm, 'shape', None)}")
    bc = cfg.blocks
    step = 2
    z_half = height_map_m(depth_mm[::step, ::step].astype(np.float32) / 1000.0, cal.K / np.array([[step], [step], [1]]), cal.T_world_camera)
    with np.errstate(invalid="ignore"):
        raised = (z_half > bc.min_height_m) & (z_half < bc.max_height_m)
    hsv_half = cv2.cvtColor(color_bgr[::step, ::step], cv2.COLOR_BGR2HSV)
    lut, names = hue_lut(cfg)
    classes = color_classes(hsv_half, cfg, lut)
    classes[~raised] = 0
    detector = tag_detector
    blocks: list[Block] = []
    for ci, name in enumerate(names, start=1):
        mask = (classes == ci).astype(np.uint8)
        if not mask.any():
            continue
        n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        for k in range(1, n):
            if stats[k, cv2.CC_STAT_AREA] < 12:
                continue
            top_m = float(np.nanpercentile(z_half[labels == k], 90))
            x, y, bw, bh = stats[k, :4]
            roi = (max(0, x * step - 8), max(0, y * step - 8), min(w, (x + bw) * step + 8), min(h, (y + bh) * step + 8))
            for block in _blocks_from_region(color_bgr, depth_mm, cal, cfg, roi, top_m, name, ci, lut, z_half, step):
                if block.aruco_id is None and _face_looks_tagged(color_bgr, block):
                    detector = detector or make_detector(cfg.tags.block_tag_dictionary)
                    block = _with_tag(block, color_bgr, roi, detector, cfg)
                if not any(np.linalg.norm(block.position_m[:2] - b.position_m[:2]) < 0.01 for b in blocks):
                    blocks.append(block)
    return sorted(blocks, key=lambda b: (round(float(b.position_m[1]), 3), float(b.position_m[0])))


def _blocks_from_region(color_bgr, depth_mm, cal, cfg, roi, top_m, name, ci, lut, z_half, step) -> list[Block]:
    """The top face at about top_m in the ROI (pixels of this colour or colourless, e.g. a tag), as blocks."""
    x0, y0, x1, y1 = roi
    classes = color_classes(cv2.cvtColor(color_bgr[y0:y1, x0:x1], cv2.COLOR_BGR2HSV), cfg, lut)
    keep = (classes == ci) | (classes == 0)
    z = _roi_heights(depth_mm, cal, roi)
    found = _top_face_in_roi(z, roi, top_m, keep, cfg.blocks.top_face_tolerance_m)
    if found is None:
        return []
    pixels, contour, face_m = found
    face = _face_from_pixels(pixels, contour, face_m, cal)
    small = cfg.blocks.small_size_m
    if face.pixel_count * face.pixel_area_m2 < 0.3 * small * small:
        return []  # a sliver: the edge of a lower stack member or noise
    if _covered(face, cal, z, roi):
        return []  # a lower member of a stack: something sits on its centre
    if (classes[pixels[:, 1].astype(int) - y0, pixels[:, 0].astype(int) - x0] == ci).mean() < 0.15:
        return []  # the face is mostly another object's colourless top
    parts = [face] if _classify_face(face, cfg)[3] else _split_touching(face, cfg)
    return [_make_block(part, name, cal, cfg, z_half, step) for part in parts]


def _covered(face: _Face, cal: Calibration, z: np.ndarray, roi) -> bool:
    """True if the image point of the face's centroid shows something well above the face."""
    centre = np.array([[*face.points_xy.mean(axis=0), face.top_m]])
    u, v = project_points(cal.T_world_camera, cal.K, cal.dist, centre)[0]
    ui, vi = int(round(u)) - roi[0], int(round(v)) - roi[1]
    if not (0 <= vi < z.shape[0] and 0 <= ui < z.shape[1]):
        return False
    value = z[vi, ui]
    return bool(np.isfinite(value) and value > face.top_m + 0.01)


def _face_looks_tagged(color_bgr: np.ndarray, block: Block) -> bool:
    """A top face with a bright colourless patch in the middle may carry a tag."""
    u, v = block.center_px.astype(int)
    patch = color_bgr[max(0, v - 4) : v + 5, max(0, u - 4) : u + 5]
    if patch.size == 0:
        return False
    hsv = cv2.cvtColor(patch, cv2.COLOR_BGR2HSV)
    return bool(np.mean(hsv[..., 1] < 60) > 0.5)


def _with_tag(block: Block, color_bgr: np.ndarray, roi, detector, cfg: PerceptionConfig) -> Block:
    """The block with its top tag's id, colour and destination (config), if a tag is found on it."""
    x0, y0, x1, y1 = roi
    crop = cv2.resize(color_bgr[y0:y1, x0:x1], None, fx=2.0, fy=2.0, interpolation=cv2.INTER_CUBIC)
    for tag in detect_tags(crop, detector=detector) if min(crop.shape[:2]) >= 16 else []:
        centre = tag.center_px / 2.0 + np.array([x0, y0])
        if np.linalg.norm(centre - block.center_px) < 0.5 * np.ptp(block.contour_px, axis=0).max():
            entry = cfg.tags.block_tags.get(tag.id)
            return replace(
                block,
                aruco_id=tag.id,
                color=entry.color if entry else block.color,
                destination=entry.destination if entry else None,
            )
    return block


def _make_block(face: _Face, color: str, cal, cfg, z_half, step) -> Block:
    size, side, yaw, is_cube, centre_xy = _classify_face(face, cfg)
    level, sizes, _ = stack_from_height(face.top_m, size, cfg)
    occluded = _is_occluded(face, size, cfg, z_half, step)
    position = np.array([centre_xy[0], centre_xy[1], face.top_m])
    return Block(
        color=color,
        size=size,
        position_m=position,
        yaw_rad=float(yaw),
        height_m=float(face.top_m),
        stack_level=int(level),
        center_px=face.center_px,
        contour_px=face.contour_px,
        is_cube=bool(is_cube),
        occluded=bool(occluded),
        side_m=float(side),
        stack_sizes=sizes,
    )


def _is_occluded(face: _Face, size: str, cfg: PerceptionConfig, z_half: np.ndarray, step: int) -> bool:
    """True when something well above the face (the arm) borders it in the image and hides part of it."""
    edge = cfg.blocks.large_size_m if size == "large" else cfg.blocks.small_size_m
    coverage = face.pixel_count * face.pixel_area_m2 / (edge * edge)
    if coverage > 0.8:
        return False
    c = (face.contour_px / step).astype(np.int32)
    x0, y0 = np.maximum(c.min(axis=0) - 4, 0)
    x1, y1 = c.max(axis=0) + 5
    with np.errstate(invalid="ignore"):
        return bool(np.any(z_half[y0:y1, x0:x1] > face.top_m + 0.015))
