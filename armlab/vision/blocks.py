"""Block detection from colour + depth: colour class, size class from the metric footprint, top-face
centre and yaw in the world, stack level from height, touching same-colour blocks split, arm
occlusion flagged, distractors rejected, and tag-topped blocks identified. A top face the image's edge
cuts (a tall stack's top leaving the camera's view) is measured from the edges that show
(clipped_face.py), or flagged occluded when they do not fix it.

Speed: colour and height are computed at quarter resolution to find candidates; each candidate's top
face is then measured on a full-resolution region of interest.
"""

from __future__ import annotations

import copy
import math
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import lru_cache

import cv2
import numpy as np

from armlab.vision.board_plane import BoardPlane, BoardPlaneError, BoardPlaneFitter
from armlab.vision.calibration import Calibration
from armlab.vision.clipped_face import fit_clipped_square, on_image_border
from armlab.vision.colors import BoardGrey, ColorModel, board_region_mask
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import PlaneCamera, height_coefficients, height_map_m
from armlab.vision.tags import check_color_image, detect_tags, make_detector

# Shape of a top face, from ideal shapes with room for real edges: area / minimum-area rectangle
# (square 1, disc 0.785, triangle 0.5; real cube tops, edges worn and trimmed by depth smoothing, 0.77-0.91
# on the ROB 550 frames) and area / minimum enclosing circle (square 2/pi = 0.64, disc 1: a disc fills
# its rectangle like a worn square but its circle far more).
MIN_FILL = 0.70
SPLIT_MIN_FILL = 0.84  # a part split off a wider face: quarter discs (a semicircle cut in two) fill 0.785
MAX_CIRCLE_FILL = 0.82
MAX_ASPECT = 1.3
SIZE_TOLERANCE = 0.22  # measured side within this fraction of the class size
SPLIT_SIZE_TOLERANCE = 0.12  # each side of a part split from touching cubes, within this of the edge
BORDER_MARGIN_PX = 2  # a face with pixels this close to the image's edge runs off the image
MAX_EDGE_RESIDUAL = 0.025  # a cut face's outline this close to a square's edges on average (x edge): cubes ~0.013, discs ~0.036


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
    seen_time_s: float | None = None  # capture time (time.time()) of the frame it was seen in
    seen_arm_joints_rad: tuple[float, ...] | None = None  # the measured arm joints at that frame
    color_lab: tuple[float, float, float] | None = None  # the top face's board-normalised CIELAB (armlab.vision.colors)

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
            "seen_time_s": self.seen_time_s,
            "seen_arm_joints_rad": None if self.seen_arm_joints_rad is None else list(self.seen_arm_joints_rad),
            "color_lab": None if self.color_lab is None else [float(x) for x in self.color_lab],
        }


def quantile(values: np.ndarray, q: float) -> float:
    """The q-quantile (0..1) of a non-empty array by partial sort: far cheaper than np.percentile on small arrays."""
    flat = np.asarray(values).ravel()
    k = int(round(q * (flat.size - 1)))
    return float(np.partition(flat, k)[k])


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


def _class_table(lut: np.ndarray) -> np.ndarray:
    """hue_lut's table as cv2.LUT wants it: 256 entries of colour index + 1."""
    table = np.empty(256, np.uint8)
    table[:180] = lut + 1
    table[180:] = table[179]
    return table


def _color_classes(hsv: np.ndarray, cfg: PerceptionConfig, table: np.ndarray) -> np.ndarray:
    """Per-pixel colour index + 1 (0 = not a block colour: grey, dark or washed out).

    Two OpenCV passes: the _class_table on the hue plane (hues past 179 count as 179), and a range
    mask for enough saturation and value."""
    classes = cv2.LUT(cv2.extractChannel(hsv, 0), table)
    colourful = cv2.inRange(hsv, (0, cfg.blocks.min_saturation, cfg.blocks.min_value), (255, 255, 255))
    return cv2.bitwise_and(classes, colourful)


def stack_candidates(top_m: float, top_size: str, cfg: PerceptionConfig) -> list[tuple[float, tuple[str, ...]]]:
    """(height mismatch m, sizes bottom..top) of every pile explaining a top face at top_m, best first.

    Piles hold large blocks below small ones, so the blocks under a large block are large. Piles up to
    the configured max_height_m are considered (a to_the_sky tower of 14 large blocks is 0.53 m).
    """
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    below = top_m - (large if top_size == "large" else small)
    n_large = int(cfg.blocks.max_height_m // large) + 1  # 0 .. n_large - 1 large blocks below
    n_small = int(cfg.blocks.max_height_m // small) + 1 if top_size == "small" else 1
    errors = np.abs(below - _pile_heights(large, small, n_large, n_small))
    order = np.argsort(errors, kind="stable")[:6].tolist()
    return [(float(errors[i]), ("large",) * (i // n_small) + ("small",) * (i % n_small) + (top_size,)) for i in order]


@lru_cache(maxsize=16)
def _pile_heights(large: float, small: float, n_large: int, n_small: int) -> np.ndarray:
    """Heights of piles of 0..n_large-1 large then 0..n_small-1 small blocks, flattened (read-only)."""
    heights = np.add.outer(np.arange(n_large) * large, np.arange(n_small) * small).ravel()
    heights.flags.writeable = False
    return heights


def stack_from_height(top_m: float, top_size: str, cfg: PerceptionConfig) -> tuple[int, tuple[str, ...], float]:
    """(stack level, sizes bottom..top, height mismatch m) of the pile that best explains the top height."""
    err, sizes = stack_candidates(top_m, top_size, cfg)[0]
    return len(sizes), sizes, err


def _transition_m(sizes: tuple[str, ...], cfg: PerceptionConfig) -> float | None:
    """Height of the last large block's top when small blocks sit on it (an exposed ring), else None."""
    if "large" not in sizes or sizes[-1] == "large":
        return None
    return sizes.count("large") * cfg.blocks.large_size_m


def choose_stack(
    top_m: float, top_size: str, cfg: PerceptionConfig, z_roi: np.ndarray | None, ring_px: float,
    candidates: list[tuple[float, tuple[str, ...]]] | None = None,
) -> tuple[str, ...]:
    """The pile (sizes bottom..top) for a top face: by height, and where two piles fit about equally
    (e.g. 2 large + 1 small vs 4 small under a small top), by whether a large block's ring shows.
    candidates: stack_candidates(top_m, top_size, cfg) if the caller already has them."""
    candidates = candidates or stack_candidates(top_m, top_size, cfg)
    best_err = candidates[0][0]
    close = [c for c in candidates if c[0] <= best_err + 0.0025][:4]
    if len(close) == 1 or z_roi is None:
        return close[0][1]

    def ring_seen(height_m: float) -> bool:
        return int(np.count_nonzero(np.abs(z_roi - height_m) < 0.0015)) >= ring_px

    transitions = {c[1]: _transition_m(c[1], cfg) for c in close}
    seen = {h: ring_seen(h) for h in transitions.values() if h is not None}
    for err, sizes in close:
        h = transitions[sizes]
        consistent = seen[h] if h is not None else not any(seen.values())
        if consistent:
            return sizes
    return close[0][1]


@dataclass
class _Face:
    """A measured flat top face before classification."""

    points_xy: np.ndarray  # (N, 2) world
    top_m: float
    contour_px: np.ndarray
    center_px: np.ndarray
    pixel_count: int
    pixel_area_m2: float
    plane_H: np.ndarray | None = None  # PlaneCamera.homography(top_m)
    pixels_px: np.ndarray | None = None  # (N, 2) full-resolution (u, v) of points_xy
    classes: np.ndarray | None = None  # (N,) colour index + 1 of those pixels (0: colourless)


def _measure_rect(points_xy: np.ndarray, pitch_m: float) -> tuple[np.ndarray, float, float, float, float]:
    """(centre xy, side_a, side_b, yaw mod pi/2 in [-pi/4, pi/4), fill) of a point set's minimum rectangle."""
    (cx, cy), (wa, wb), angle_deg = cv2.minAreaRect(points_xy.astype(np.float32))
    wa, wb = wa + pitch_m, wb + pitch_m  # pixel centres sit half a pixel inside the edges
    yaw = math.radians(angle_deg)
    yaw = (yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4
    fill = points_xy.shape[0] * pitch_m * pitch_m / max(wa * wb, 1e-12)
    return np.array([cx, cy]), wa, wb, yaw, fill


def circle_fill(points_xy: np.ndarray, pitch_m: float) -> float:
    """A point set's area / its minimum enclosing circle's (square 0.64, disc 1)."""
    _, radius = cv2.minEnclosingCircle(points_xy.astype(np.float32))
    radius += 0.5 * pitch_m
    return points_xy.shape[0] * pitch_m * pitch_m / max(math.pi * radius * radius, 1e-12)


@dataclass(frozen=True)
class _Classified:
    size: str
    side_m: float
    yaw: float
    is_cube: bool
    centre_xy: np.ndarray
    stacks: list[tuple[float, tuple[str, ...]]]  # stack_candidates(top, size), best first


def _classify_face(face: _Face, cfg: PerceptionConfig) -> _Classified:
    """Size, side, yaw, cube or not, centre and candidate stacks from the face's metric footprint and height."""
    pitch = math.sqrt(face.pixel_area_m2)
    centre, wa, wb, yaw, fill = _measure_rect(face.points_xy, pitch)
    side = math.sqrt(wa * wb)
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    size = "large" if abs(side - large) < abs(side - small) else "small"
    edge = large if size == "large" else small
    stacks = stack_candidates(face.top_m, size, cfg)
    height_err = stacks[0][0]
    is_cube = (
        fill >= MIN_FILL
        and circle_fill(face.points_xy, pitch) <= MAX_CIRCLE_FILL
        and max(wa, wb) / max(min(wa, wb), 1e-9) <= MAX_ASPECT
        and abs(side - edge) <= SIZE_TOLERANCE * edge
        and height_err <= cfg.blocks.stack_height_tolerance_m
    )
    centroid = face.points_xy.mean(axis=0)
    return _Classified(size, side, yaw, is_cube, centroid if is_cube else centre, stacks)


def _part(face: _Face, sel: np.ndarray) -> _Face:
    """The part `sel` (bool over the face's points) of a face, with its own pixel centre and outline."""
    if face.pixels_px is None or not sel.any():
        return _Face(face.points_xy[sel], face.top_m, face.contour_px, face.center_px, int(sel.sum()), face.pixel_area_m2, face.plane_H)
    px = face.pixels_px[sel]
    hull = cv2.convexHull(px.astype(np.float32)).reshape(-1, 2).astype(np.float64)
    return _Face(face.points_xy[sel], face.top_m, hull, px.mean(axis=0), int(sel.sum()), face.pixel_area_m2, face.plane_H,
                 px, None if face.classes is None else face.classes[sel])


def face_colour(classes: np.ndarray | None, fallback: int) -> int:
    """The colour index + 1 most of a face's coloured pixels have (fallback when none is coloured)."""
    if classes is None:
        return fallback
    counts = np.bincount(classes, minlength=fallback + 1)
    counts[0] = 0
    return int(np.argmax(counts)) if counts.sum() else fallback


def _split_touching(face: _Face, cfg: PerceptionConfig) -> list[_Face]:
    """Split a face holding several touching same-colour cubes by k-means on its points; [face] if no split fits."""
    area = face.pixel_count * face.pixel_area_m2
    candidates = []
    for edge in (cfg.blocks.large_size_m, cfg.blocks.small_size_m):
        n = int(round(area / (edge * edge)))
        if 2 <= n <= 6:
            candidates.append(n)
    pts = face.points_xy.astype(np.float32)
    centred = pts - pts.mean(axis=0)
    axis = np.linalg.svd(centred, full_matrices=False)[2][0]  # the row of cubes lies along this axis
    along = centred @ axis
    pitch = math.sqrt(face.pixel_area_m2)
    for n in candidates:
        # Deterministic start: n equal slices along the main axis, then k-means refines the split.
        labels = np.minimum((np.argsort(np.argsort(along)) * n) // len(along), n - 1).astype(np.int32).reshape(-1, 1)
        criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-5)
        _, labels, _ = cv2.kmeans(pts, n, labels, criteria, 1, cv2.KMEANS_USE_INITIAL_LABELS)
        parts = []
        for k in range(n):
            sel = labels.ravel() == k
            parts.append(_part(face, sel))

        def fits(part: _Face) -> bool:
            classified = _classify_face(part, cfg)
            edge = cfg.blocks.large_size_m if classified.size == "large" else cfg.blocks.small_size_m
            _, wa, wb, _, _ = _measure_rect(part.points_xy, pitch)
            fill = _measure_rect(part.points_xy, pitch)[4]
            return classified.is_cube and fill >= SPLIT_MIN_FILL and max(abs(wa - edge), abs(wb - edge)) <= SPLIT_SIZE_TOLERANCE * edge

        if all(fits(p) for p in parts):
            return parts
    return [face]


STEP = 4  # candidates at quarter resolution (a small cube's top is still ~6x6 px); measured at full


class BlockGeometry:
    """What detect_blocks needs from a calibration, computed once: the plane mapper, the board-plane
    fitter's per-pixel terms and, for heights above a plane (row = (n, D): height = n . X + D for depth
    camera points X), the terms of the quarter-resolution height map and, per full-resolution column
    and row, of a pixel's height. Built for the calibration's depth model (T_world_depth); with_heights
    gives the same for the board plane fitted in a frame. Read-only once built."""

    def __init__(self, cal: Calibration, cfg: PerceptionConfig | None = None) -> None:
        K = cal.K
        self.calibration = cal
        self.camera = PlaneCamera(cal.T_world_camera, K, cal.dist)
        self.small_shape = (-(-cal.height // STEP), -(-cal.width // STEP))  # of image[::STEP, ::STEP]
        self.small_K = K / np.array([[STEP], [STEP], [1]])
        self.fitter = None
        if cfg is not None and cfg.board_plane.enabled:
            self.fitter = BoardPlaneFitter(K, cal.dist, cal.T_world_depth, cal.width, cal.height,
                                           cfg.board.x_range_m, cfg.board.y_range_m, step=STEP)
        self._set_heights(cal.T_world_depth[2])
        self.plane: BoardPlane | None = None  # the frame's board plane, when with_heights made this

    def _set_heights(self, row: np.ndarray) -> None:
        K, cal = self.calibration.K, self.calibration
        T = np.eye(4)
        T[2] = row
        self.small_coefficients = height_coefficients(self.small_shape, self.small_K, T)
        r3 = np.asarray(row[:3], dtype=np.float32)
        self.height_row = T
        self.height_u = r3[0] * ((np.arange(cal.width, dtype=np.float32) - K[0, 2]) / K[0, 0])
        self.height_v = r3[1] * ((np.arange(cal.height, dtype=np.float32) - K[1, 2]) / K[1, 1])
        self.height_1 = r3[2]
        self.height_t = np.float32(row[3])

    def with_heights(self, plane: BoardPlane) -> "BlockGeometry":
        """A copy measuring heights from `plane` (a board plane fitted in the depth camera's frame)."""
        other = copy.copy(self)
        other._set_heights(plane.height_row())
        other.plane = plane
        return other


def frame_geometry(geo: BlockGeometry, depth_m_small: np.ndarray, cfg: PerceptionConfig,
                   exclude_small: np.ndarray | None = None) -> BlockGeometry:
    """geo measuring heights from the board plane fitted in this frame's depth (quarter resolution, in
    metres), so heights follow the depth camera's own board; geo itself (the calibration's depth model)
    when the fit is disabled or finds no dominant board plane (the board hidden, no depth)."""
    if geo.fitter is None:
        return geo
    bp = cfg.board_plane
    try:
        plane = geo.fitter.fit(depth_m_small, bp.window_m, bp.inlier_m, exclude_small, bp.min_inlier_fraction)
    except BoardPlaneError:
        return geo
    return geo.with_heights(plane)


def _roi_heights(depth_mm: np.ndarray, geo: BlockGeometry, roi: tuple[int, int, int, int]) -> np.ndarray:
    """World z (m) of a region of interest from 3x3-median-filtered depth (edges kept, noise about halved)."""
    x0, y0, x1, y1 = roi
    d = cv2.medianBlur(depth_mm[y0:y1, x0:x1], 3).astype(np.float32) / 1000.0
    z = d * (geo.height_u[None, x0:x1] + geo.height_v[y0:y1, None] + geo.height_1) + geo.height_t
    z[d <= 0] = np.nan
    return z


def _largest_blob(mask: np.ndarray) -> np.ndarray | None:
    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=4)
    if n <= 1:
        return None
    return (labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))).view(np.uint8)


def _seeded_blob(mask: np.ndarray, seed: np.ndarray | None) -> np.ndarray | None:
    """The connected part of mask holding most seed pixels (the largest when no seed pixel is in it)."""
    if seed is None:
        return _largest_blob(mask)
    n, labels = cv2.connectedComponents(mask.view(np.uint8), connectivity=4)
    if n <= 1:
        return None
    hits = np.bincount(labels[seed & mask.view(bool)], minlength=n)
    if hits[1:].max() == 0:
        return _largest_blob(mask)
    return (labels == 1 + int(np.argmax(hits[1:]))).view(np.uint8)


def _top_face_in_roi(
    z: np.ndarray, band: np.ndarray, keep: np.ndarray, tol_m: float, seed: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float] | None:
    """ROI pixels (rows, columns), contour (ROI coordinates) and median height of the flat face in the
    band of heights z within tol_m of the guess (band), among the pixels to keep.

    Two passes: the loose band finds the face, a tight band around its median keeps only the face
    (side-face pixels just below the top edge would bias the footprint toward the camera).
    """
    blob = _seeded_blob(band & keep, seed)
    if blob is None:
        return None
    face_m = quantile(z[blob.view(bool)], 0.5)
    blob &= (np.abs(z - face_m) < 0.5 * tol_m).view(np.uint8)
    if not blob.any():
        return None
    contours, _ = cv2.findContours(blob, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    contour = max(contours, key=cv2.contourArea)
    # Holes inside the outline (a highlight, a knot in the wood, a depth dropout) are the face too.
    filled = np.zeros_like(blob)
    cv2.drawContours(filled, [contour], -1, 1, thickness=cv2.FILLED)
    ys, xs = np.nonzero(filled)
    zs = z[ys, xs]
    return ys, xs, contour, quantile(zs[np.isfinite(zs)], 0.5) if np.isfinite(zs).any() else face_m


def _face_from_pixels(ys: np.ndarray, xs: np.ndarray, roi, contour: np.ndarray, top_m: float, camera: PlaneCamera) -> _Face:
    """The face of full-res pixels (ROI rows ys, columns xs; contour in ROI coordinates) on the plane z = top_m."""
    x0, y0 = roi[0], roi[1]
    n = len(xs)
    # Pixel centroid: the coordinates are integers, so their float sums are exact in any order.
    u, v = float(xs.sum() + n * x0) / n, float(ys.sum() + n * y0) / n
    pixels = np.empty((n + 3, 2))
    pixels[:n, 0] = xs + x0
    pixels[:n, 1] = ys + y0
    pixels[n:] = [[u, v], [u + 1, v], [u, v + 1]]
    H = None if camera.distorted else camera.homography(top_m)
    world_xy = camera.to_plane(pixels, top_m, H)
    # Footprint of one pixel on the face's plane, from the local Jacobian at the face's mean pixel.
    du, dv = world_xy[-2] - world_xy[-3], world_xy[-1] - world_xy[-3]
    pixel_area = float(abs(du[0] * dv[1] - du[1] * dv[0]))
    contour_px = contour.reshape(-1, 2) + np.array([x0, y0])
    return _Face(world_xy[:-3], top_m, contour_px.astype(np.float64), np.array([u, v]), n, pixel_area, H, pixels[:n])


def detect_blocks(
    color_bgr: np.ndarray,
    depth_mm: np.ndarray,
    cal: Calibration,
    cfg: PerceptionConfig,
    tag_detector: cv2.aruco.ArucoDetector | None = None,
    geometry: BlockGeometry | None = None,
    ignore_mask: np.ndarray | None = None,
    color_model: ColorModel | None = None,
) -> list[Block]:
    """Blocks (top of each stack) and flagged non-cubes on the board, sorted by y then x.

    tag_detector: a prebuilt detector for the block-tag dictionary (saves its construction per frame).
    geometry: BlockGeometry(cal), if the caller keeps one per calibration (saves its computation per frame).
    ignore_mask: (H, W) bool pixels that are not the scene (the robot self-filter's mask): no face is
    built from them, and a block partly hidden under them, or partly inside them, is flagged occluded.
    color_model: names each face's colour from its pixels and the board's grey around it (default: the
    config's, armlab.vision.colors); the hue classes only find candidate pixels.
    """
    check_color_image(color_bgr)
    if color_bgr.ndim != 3:
        raise ValueError("detect_blocks needs a BGR colour image")
    h, w = color_bgr.shape[:2]
    if (w, h) != (cal.width, cal.height):
        raise ValueError(f"image is {w}x{h} but the calibration is for {cal.width}x{cal.height}")
    if not isinstance(depth_mm, np.ndarray) or depth_mm.shape != (h, w) or depth_mm.dtype != np.uint16:
        raise ValueError(f"depth must be a uint16 (H, W) = ({h}, {w}) image in mm, got {getattr(depth_mm, 'shape', None)}")
    if ignore_mask is not None and (not isinstance(ignore_mask, np.ndarray) or ignore_mask.shape != (h, w) or ignore_mask.dtype != bool):
        raise ValueError(f"ignore_mask must be a bool (H, W) = ({h}, {w}) array, got {getattr(ignore_mask, 'shape', None)}")
    bc = cfg.blocks
    if geometry is None or geometry.calibration is not cal:
        geometry = BlockGeometry(cal, cfg)
    geo, step = geometry, STEP
    depth_small = depth_mm[::step, ::step].astype(np.float32)
    depth_small /= 1000.0
    geo = frame_geometry(geo, depth_small, cfg, None if ignore_mask is None else ignore_mask[::step, ::step])
    z_small = height_map_m(depth_small, geo.small_K, geo.height_row, coefficients=geo.small_coefficients)
    raised = (z_small > bc.min_height_m) & (z_small < bc.max_height_m)
    lut, names = hue_lut(cfg)
    # Every step-th pixel: nearest-neighbour resizing by an integer factor picks exactly those, and
    # far faster than copying the strided view.
    small_bgr = cv2.resize(color_bgr, geo.small_shape[::-1], interpolation=cv2.INTER_NEAREST)
    hsv_small = cv2.cvtColor(small_bgr, cv2.COLOR_BGR2HSV)
    table = _class_table(lut)
    classes = _color_classes(hsv_small, cfg, table)
    colourless = classes == 0  # e.g. the white and black of a tag on a block's top
    classes[~raised] = 0
    # The board's own brightness (median value of its pixels in this frame): the scale a block's
    # colourfulness is judged on (lighting and exposure change both alike).
    with np.errstate(invalid="ignore"):
        board_px = np.abs(z_small[::2, ::2]) < cfg.board_plane.inlier_m
    board_value = quantile(hsv_small[::2, ::2, 2][board_px], 0.5) if np.count_nonzero(board_px) >= 20 else 255.0
    z_cover = z_small  # what may hide part of a face: what stands above it, and the robot
    if ignore_mask is not None:  # the robot: neither colour nor a tag's white
        ignored_small = ignore_mask[::step, ::step]
        classes[ignored_small] = 0
        colourless[ignored_small] = False
        z_cover = z_small.copy()
        z_cover[ignored_small] = np.inf
    board_small = (z_small < bc.min_height_m) & (z_small > -0.03)  # at the board (or its depth offset): the colour model's grey
    board_small &= board_region_mask(z_small.shape, cal.T_world_camera, cal.K, cal.dist, cfg.board.x_range_m, cfg.board.y_range_m, step)
    if ignore_mask is not None:
        board_small &= ~ignore_mask[::step, ::step]
    colour_of = _face_colour(color_model or ColorModel.from_config(cfg), BoardGrey(small_bgr, board_small, scale=step))
    coloured = (classes > 0).astype(np.uint8)
    # A tag on a block's top is white and black: bridge its white (next to colour, never the dark arm)
    # so the thin coloured ring around it stays one candidate at this resolution.
    near_colour = cv2.dilate(coloured, np.ones((7, 7), np.uint8)) > 0
    candidates = coloured | (raised & colourless & near_colour & (hsv_small[..., 2] >= 150)).astype(np.uint8)
    # Grana's block-based labelling: the same labels as the default (Spaghetti) here, about 3x faster.
    n, labels, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(candidates, 8, cv2.CV_32S, cv2.CCL_GRANA)
    stats_list = stats.tolist()  # plain ints: cheaper arithmetic and slicing than numpy scalars
    pixel_m = abs(float(cal.T_world_camera[2, 3])) / cal.K[0, 0] * step  # board-level pixel size, roughly
    min_face_px = 0.25 * bc.small_size_m**2 / pixel_m**2
    detector = tag_detector
    blocks: list[Block] = []
    for k in range(1, n):
        x, y, bw, bh, area = stats_list[k]
        if area < 4:
            continue
        sel = labels[y : y + bh, x : x + bw] == k
        comp_classes = classes[y : y + bh, x : x + bw][sel]
        comp_z = z_small[y : y + bh, x : x + bw][sel]
        counts = np.bincount(comp_classes, minlength=len(names) + 1)
        roi = (max(0, x * step - 8), max(0, y * step - 8), min(w, (x + bw) * step + 8), min(h, (y + bh) * step + 8))
        ys, xs = np.nonzero(sel)
        box_z = z_small[y : y + bh, x : x + bw]
        box_colourless = colourless[y : y + bh, x : x + bw]
        tops: dict[int, tuple[float, np.ndarray, np.ndarray]] = {}  # colour -> (top, centroid, bbox)
        coloured_area = max(1, area - int(counts[0]))
        for ci in np.nonzero(counts[1:] >= max(3, 0.1 * coloured_area))[0] + 1:
            mine = comp_classes == ci
            top_m = quantile(comp_z[mine], 0.9)
            layer = mine & (np.abs(comp_z - top_m) < bc.top_face_tolerance_m)
            tag_layer = box_colourless & (np.abs(box_z - top_m) < bc.top_face_tolerance_m)
            if np.count_nonzero(layer) + np.count_nonzero(tag_layer) < min_face_px:
                continue  # only a sliver of this colour at its top: the side of a lower stack member
            pts = np.stack([xs[layer], ys[layer]], axis=1)
            tops[int(ci)] = (top_m, pts.mean(axis=0), np.concatenate([pts.min(axis=0) - 1, pts.max(axis=0) + 1]))
        region = None  # the ROI's colour and heights, shared by the colours of this component
        for ci, (top_m, _, box) in tops.items():
            if any(
                other_top > top_m + 0.01 and box[0] <= centre[0] <= box[2] and box[1] <= centre[1] <= box[3]
                for cj, (other_top, centre, _) in tops.items() if cj != ci
            ):
                continue  # a lower member of a stack: the block on top sits inside its footprint
            region = region or _Region(color_bgr, depth_mm, geo, cfg, roi, table, ignore_mask)
            region.board_value = board_value
            region.coloured_small = coloured
            for block, looks_tagged in _blocks_from_region(color_bgr, geo, cfg, region, top_m, names, ci, z_cover, step, colour_of):
                if block.aruco_id is None and looks_tagged:
                    detector = detector or make_detector(cfg.tags.block_tag_dictionary)
                    block = _with_tag(block, color_bgr, roi, detector, cfg)
                twins = [b for b in blocks if np.linalg.norm(block.position_m[:2] - b.position_m[:2]) < 0.015]
                if not twins:
                    blocks.append(block)
                elif all(block.height_m > b.height_m + 0.01 for b in twins):  # keep a stack's top only
                    blocks = [b for b in blocks if not any(b is twin for twin in twins)] + [block]
    return sorted(blocks, key=lambda b: (round(float(b.position_m[1]), 3), float(b.position_m[0])))


class _Region:
    """A region of interest at full resolution: its HSV image, colour classes and world heights."""

    def __init__(self, color_bgr: np.ndarray, depth_mm: np.ndarray, geo: BlockGeometry, cfg: PerceptionConfig, roi, table: np.ndarray,
                 ignore_mask: np.ndarray | None = None) -> None:
        x0, y0, x1, y1 = roi
        self.roi = roi
        self.board_value = 255.0
        self.coloured_small: np.ndarray | None = None  # the frame's block-coloured pixels at STEP
        self.hsv = cv2.cvtColor(color_bgr[y0:y1, x0:x1], cv2.COLOR_BGR2HSV)
        self.classes = _color_classes(self.hsv, cfg, table)
        self.colourless = self.classes == 0
        self.z = _roi_heights(depth_mm, geo, roi)
        if ignore_mask is not None:  # the robot: no height, so it neither forms a face nor covers one
            ignored = ignore_mask[y0:y1, x0:x1]
            self.classes[ignored] = 0
            self.colourless[ignored] = False
            self.z[ignored] = np.nan


def _face_colour(model: ColorModel, grey: BoardGrey):
    """colour_of(face_bgr, centre_px) -> ColorReading: the model's reading against the board's grey near the face."""
    return lambda face_bgr, centre_px: model.classify(face_bgr, grey.near(centre_px))


def _blocks_from_region(color_bgr, geo: BlockGeometry, cfg, region: _Region, top_m, names, ci, z_small, step,
                        colour_of=None) -> list[tuple[Block, bool]]:
    """The top face at about top_m in the ROI that holds this colour's top pixels, as blocks, each with
    whether its face looks tagged (_face_looks_tagged). The face is every block-coloured (or
    colourless, e.g. a tag) pixel at that height connected to them: a cube whose top reads as two hues
    (real yellow next to orange, a shaded edge) stays one face, touching cubes form one face that is
    then split by their footprints; each face or part is named by colour_of (_face_colour: the colour
    model on its block-coloured pixels, a tag's black and white left out), else by its pixels' majority hue class."""
    roi, hsv, classes, z = region.roi, region.hsv, region.classes, region.z
    tol = cfg.blocks.top_face_tolerance_m
    mine = classes == ci
    band = np.abs(z - top_m) < tol
    seed = mine & band
    # Lit from above, a top face is brighter than the block's sides: dim pixels of a colour are side
    # faces that the depth filter smeared up to the top's height at the edge facing the camera. Each
    # colour is compared with its own brightest top pixels (a blue top is darker than a yellow one).
    value = hsv[..., 2]
    keep = region.colourless.copy()
    for cj in np.unique(classes[band]):
        if cj == 0:
            continue
        colour = classes == cj
        top = colour & band
        if np.count_nonzero(top) >= 10:
            keep |= colour & (value >= 0.7 * quantile(value[top], 0.95))
        else:
            keep |= colour
    found = _top_face_in_roi(z, band, keep, tol, seed)
    if found is None:
        return []
    ys, xs, contour, face_m = found
    face_classes = classes[ys, xs]
    if np.count_nonzero(face_classes) / len(ys) < 0.15:
        return []  # the face is mostly another object's colourless top
    face = _face_from_pixels(ys, xs, roi, contour, face_m, geo.camera)
    face.classes = face_classes
    small = cfg.blocks.small_size_m
    if face.pixel_count * face.pixel_area_m2 < 0.3 * small * small:
        return []  # a sliver: the edge of a lower stack member or noise
    if _covered(contour, face_m, z):
        return []  # a lower member of a stack: something sits on its centre
    part_of_more = _part_of_larger_surface(face, z_small, step, tol, region.coloured_small) or _dark_and_colourless(hsv[ys, xs], face_classes, region.board_value)

    def block_of(f: _Face, classified: _Classified | None = None, out_of_view: bool = False) -> Block:
        if colour_of is None or f.pixels_px is None:
            return _make_block(f, names[face_colour(f.classes, ci) - 1], geo.camera, cfg, z_small, step, z, classified, out_of_view)
        px = f.pixels_px.astype(np.intp)
        if f.classes is not None and np.count_nonzero(f.classes) >= 10:
            px = px[f.classes > 0]
        reading = colour_of(color_bgr[px[:, 1], px[:, 0]], f.center_px)
        block = _make_block(f, reading.name, geo.camera, cfg, z_small, step, z, classified, out_of_view)
        return replace(block, color_lab=reading.measured_lab)

    if _runs_off_image(ys, xs, roi, geo.calibration):
        # A tall stack's top partly out of view: the square from the edges that show, else flagged.
        # No tag lookup: a tag on a cut face is likely cut too.
        clipped = _classify_clipped(face, ys, xs, roi, geo, cfg)
        if clipped is None or not clipped.is_cube or part_of_more:
            return [(_not_cube(block_of(face, clipped, out_of_view=True)), False)]
        return [(block_of(face, clipped), False)]
    classified = _classify_face(face, cfg)
    if classified.is_cube:
        blocks = [block_of(face, classified)]
    else:
        blocks = [block_of(part) for part in _split_touching(face, cfg)]
    if part_of_more:
        blocks = [_not_cube(b) for b in blocks]
    return [(block, _face_looks_tagged(color_bgr, block, roi, hsv)) for block in blocks]


MIN_CHROMA = 0.15  # of the board's value: real cube tops 0.22-1.7, the dark arm's tinted parts 0.06-0.09 (ROB 550 frames)


def _dark_and_colourless(face_hsv: np.ndarray, face_classes: np.ndarray, board_value: float) -> bool:
    """True when a face's block-coloured pixels are dark and grey (chroma = saturation x value), as the
    black arm's faintly tinted parts are: their median chroma is below MIN_CHROMA of the board's value."""
    coloured = face_classes > 0
    if not coloured.any():
        return False
    hsv = face_hsv[coloured].astype(np.float32)
    chroma = hsv[:, 1] * hsv[:, 2] / 255.0
    return quantile(chroma, 0.5) < MIN_CHROMA * board_value


def _not_cube(block: Block) -> Block:
    return replace(block, is_cube=False) if block.is_cube else block


LARGER_SURFACE_RATIO = 1.5  # colourless surface at a face's height, connected to it, this many times its area: not a cube's top


def _part_of_larger_surface(face: _Face, z_small: np.ndarray, step: int, tol_m: float, coloured_small: np.ndarray | None) -> bool:
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
    with np.errstate(invalid="ignore"):
        band = (np.abs(window - face.top_m) < tol_m).astype(np.uint8)
    n, labels = cv2.connectedComponents(band, connectivity=8)
    cu, cv_ = min(int(u) - x0, window.shape[1] - 1), min(int(v) - y0, window.shape[0] - 1)
    label = labels[cv_, cu]
    if label == 0:
        return False
    surface = labels == label
    if coloured_small is not None:
        surface &= ~coloured_small[y0 : y0 + window.shape[0], x0 : x0 + window.shape[1]].astype(bool)
    return np.count_nonzero(surface) * step * step >= LARGER_SURFACE_RATIO * face.pixel_count


def _runs_off_image(ys: np.ndarray, xs: np.ndarray, roi, cal: Calibration) -> bool:
    """True when a face (ROI rows ys, columns xs) reaches within BORDER_MARGIN_PX of the image's edge."""
    x0, y0 = roi[0], roi[1]
    m = BORDER_MARGIN_PX
    return bool(
        xs.min() + x0 <= m or ys.min() + y0 <= m or xs.max() + x0 >= cal.width - 1 - m or ys.max() + y0 >= cal.height - 1 - m
    )


def _classify_clipped(face: _Face, ys: np.ndarray, xs: np.ndarray, roi, geo: BlockGeometry, cfg: PerceptionConfig) -> _Classified | None:
    """Size, side, yaw, cube or not, centre and stacks of a face the image's edge cuts, from the edges
    of its outline that show (clipped_face.fit_clipped_square); None when they do not fix the square."""
    mask = np.zeros((roi[3] - roi[1], roi[2] - roi[0]), np.uint8)
    mask[ys, xs] = 1
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    outline_px = max(contours, key=cv2.contourArea).reshape(-1, 2) + np.array(roi[:2])
    shown = ~on_image_border(outline_px, geo.calibration.width, geo.calibration.height, BORDER_MARGIN_PX)
    outline_xy = geo.camera.to_plane(outline_px.astype(np.float64), face.top_m, face.plane_H)
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    fit = fit_clipped_square(outline_xy, shown, math.sqrt(face.pixel_area_m2), (large, small), SIZE_TOLERANCE)
    if fit is None:
        return None
    size = "large" if abs(fit.side_m - large) < abs(fit.side_m - small) else "small"
    edge = large if size == "large" else small
    stacks = stack_candidates(face.top_m, size, cfg)
    is_cube = (
        abs(fit.side_m - edge) <= SIZE_TOLERANCE * edge
        and fit.edge_residual_m <= MAX_EDGE_RESIDUAL * edge
        and stacks[0][0] <= cfg.blocks.stack_height_tolerance_m
    )
    return _Classified(size, fit.side_m, fit.yaw_rad, is_cube, fit.centre_xy, stacks)


def _covered(contour: np.ndarray, top_m: float, z: np.ndarray) -> bool:
    """True for a lower member of a stack: within the face's convex hull (contour in the coordinates
    of the ROI's heights z), a sizeable part stands well above the face (the block on top)."""
    inside = np.zeros(z.shape, np.uint8)
    cv2.fillConvexPoly(inside, cv2.convexHull(contour), 1)
    inside = inside.view(bool)
    above = np.count_nonzero((z > top_m + 0.01) & inside)
    return above > 0.15 * max(1, np.count_nonzero(inside))


def _face_looks_tagged(color_bgr: np.ndarray, block: Block, roi=None, roi_hsv: np.ndarray | None = None) -> bool:
    """A top face whose middle is mostly colourless (white, grey or black: hue is noise on dark
    pixels, so they count too) may carry a tag. roi_hsv: the HSV image of the ROI, if at hand."""
    u, v = block.center_px.astype(int).tolist()
    xa, ya, xb, yb = max(0, u - 4), max(0, v - 4), u + 5, v + 5
    if roi_hsv is not None and roi[0] <= xa and roi[1] <= ya and xb <= roi[2] and yb <= roi[3]:
        hsv = roi_hsv[ya - roi[1] : yb - roi[1], xa - roi[0] : xb - roi[0]]
    else:
        patch = color_bgr[ya:yb, xa:xb]
        if patch.size == 0:
            return False
        hsv = cv2.cvtColor(patch, cv2.COLOR_BGR2HSV)
    return bool(np.mean((hsv[..., 1] < 60) | (hsv[..., 2] < 60)) > 0.5)


TAG_RETRY_SCALES = (3.0, 4.0, 1.0)  # when the 2x read finds no tag on a face: a tag of ~2 px per bit reads at some scales only


def _tag_ids_on(block: Block, color_bgr: np.ndarray, roi, detector, scale: float) -> list[int]:
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


def _with_tag(block: Block, color_bgr: np.ndarray, roi, detector, cfg: PerceptionConfig) -> Block:
    """The block with its top tag's id, colour and destination (config), if a tag is found on it: read
    from the ROI at 2x; if that finds none, at TAG_RETRY_SCALES, where an id counts when it is one of the
    configured block tags or read at two scales (a tiny tag misreads now and then, never the same way).
    A tag read at no scale (a small block's tag seen askew from far, under 2 px per bit) leaves aruco_id None;
    when exactly one configured block tag has the block's colour (the id <-> colour table of block_tags),
    the block gets that tag's destination."""
    ids = _tag_ids_on(block, color_bgr, roi, detector, 2.0)[:1]
    if not ids:
        reads = [tag_id for scale in TAG_RETRY_SCALES for tag_id in _tag_ids_on(block, color_bgr, roi, detector, scale)]
        counts = Counter(reads)
        ids = sorted((tag_id for tag_id, n in counts.items() if tag_id in cfg.tags.block_tags or n >= 2),
                     key=lambda tag_id: (-counts[tag_id], tag_id not in cfg.tags.block_tags))[:1]
    if not ids:
        by_colour = [entry for entry in cfg.tags.block_tags.values() if entry.color == block.color]
        return replace(block, destination=by_colour[0].destination) if len(by_colour) == 1 else block
    entry = cfg.tags.block_tags.get(ids[0])
    return replace(block, aruco_id=ids[0], color=entry.color if entry else block.color,
                   destination=entry.destination if entry else None)


def _make_block(face: _Face, color: str, camera: PlaneCamera, cfg, z_small, step, z_roi=None, classified: _Classified | None = None,
                out_of_view: bool = False) -> Block:
    """The block of a face (classified: its _classify_face or _classify_clipped, if at hand).
    out_of_view: part of the face is outside the image and its square is not known: flagged occluded."""
    c = classified or _classify_face(face, cfg)
    size, side, yaw, is_cube, centre_xy = c.size, c.side_m, c.yaw, c.is_cube, c.centre_xy
    ring_m2 = cfg.blocks.large_size_m**2 - cfg.blocks.small_size_m**2
    sizes = choose_stack(face.top_m, size, cfg, z_roi, 0.3 * ring_m2 / face.pixel_area_m2, c.stacks)
    occluded = out_of_view or _is_occluded(face, centre_xy, yaw, size, camera, cfg, z_small, step)
    if occluded and not is_cube:
        # Part of the face is hidden: judge by what can be seen (not larger than the cube, right height).
        edge = cfg.blocks.large_size_m if size == "large" else cfg.blocks.small_size_m
        is_cube = side <= edge * (1 + SIZE_TOLERANCE) and c.stacks[0][0] <= cfg.blocks.stack_height_tolerance_m
    return Block(
        color=color,
        size=size,
        position_m=np.array([centre_xy[0], centre_xy[1], face.top_m]),
        yaw_rad=float(yaw),
        height_m=float(face.top_m),
        stack_level=len(sizes),
        center_px=face.center_px,
        contour_px=face.contour_px,
        is_cube=bool(is_cube),
        occluded=bool(occluded),
        side_m=float(side),
        stack_sizes=sizes,
    )


def _is_occluded(face: _Face, centre_xy, yaw: float, size: str, camera: PlaneCamera, cfg: PerceptionConfig, z_small: np.ndarray, step: int) -> bool:
    """True when something well above the face (the arm) covers part of where the cube's top should be:
    the expected square, drawn around the measured centre, holds readings 15 mm or more above the face."""
    edge = cfg.blocks.large_size_m if size == "large" else cfg.blocks.small_size_m
    half = 0.5 * edge
    c, s = math.cos(yaw), math.sin(yaw)
    square = np.array([[centre_xy[0] + c * a - s * b, centre_xy[1] + s * a + c * b]
                       for a, b in ((-half, -half), (half, -half), (half, half), (-half, half))])
    poly = camera.project(square, face.top_m, face.plane_H) / step
    x0, y0 = np.maximum(np.floor(poly.min(axis=0)).astype(int) - 1, 0)
    x1, y1 = np.ceil(poly.max(axis=0)).astype(int) + 2
    window = z_small[y0:y1, x0:x1]
    if window.size == 0:
        return False
    inside = np.zeros(window.shape, np.uint8)
    cv2.fillConvexPoly(inside, np.round(poly - [x0, y0]).astype(np.int32), 1)
    above = np.count_nonzero((window > face.top_m + 0.008) & (inside > 0))
    # At least 3 samples: a small cube's square holds ~30, and one or two can be a depth dropout the
    # robot mask claims at its edge.
    return above > max(2, 0.05 * np.count_nonzero(inside))
