"""A block's top face as measured (Face) and what its metric footprint says: size class, side, yaw,
square or not (ClassifiedFace), touching cubes split by k-means, faces the image's edge cuts, and lower
stack members covered by the block on top. Pure functions of the face's points and the config."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from armlab.vision.block_geometry import BlockGeometry
from armlab.vision.calibration import Calibration
from armlab.vision.clipped_face import fit_clipped_square, on_image_border
from armlab.vision.config import PerceptionConfig
from armlab.vision.geometry import dehomogenise, inverse_homography
from armlab.vision.stacks import stack_candidates

# Shape of a top face, from ideal shapes with room for real edges: area / minimum-area rectangle
# (square 1, disc 0.785, triangle 0.5; real cube tops, edges worn and trimmed by depth smoothing, 0.77-0.91
# on the ROB 550 frames) and area / minimum enclosing circle (square 2/pi = 0.64, disc 1: a disc fills
# its rectangle like a worn square but its circle far more).
MIN_FILL = 0.70
SPLIT_MIN_FILL = 0.84  # a part split off a wider face (or the face as a whole): quarter discs (a semicircle cut in two) fill 0.785
MAX_CIRCLE_FILL = 0.82
MAX_ASPECT = 1.3
SIZE_TOLERANCE = 0.22  # measured side within this fraction of the class size
SPLIT_SIZE_TOLERANCE = 0.12  # each side of a part split from touching cubes, within this of the edge
SPLIT_SAMPLE_POINTS = 400  # a split's first k-means runs on about this many of a face's points
BORDER_MARGIN_PX = 2  # a face with pixels this close to the image's edge runs off the image
MAX_EDGE_RESIDUAL = 0.025  # a cut face's outline this close to a square's edges on average (x edge): cubes ~0.013, discs ~0.036


def quantile(values: np.ndarray, q: float) -> float:
    """The q-quantile (0..1) of a non-empty array by partial sort: far cheaper than np.percentile on small arrays."""
    flat = np.array(values).ravel()  # a copy, sorted partially in place (np.partition's copy, without its wrapper)
    k = int(round(q * (flat.size - 1)))
    flat.partition(k)
    return float(flat[k])


@dataclass
class Face:
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


def measure_rect(points_xy: np.ndarray, pitch_m: float, count: int | None = None) -> tuple[np.ndarray, float, float, float, float]:
    """(centre xy, side_a, side_b, yaw mod pi/2 in [-pi/4, pi/4), fill) of a point set's minimum rectangle.
    count: the set's size when points_xy is only its convex hull (face_hull_xy)."""
    (cx, cy), (wa, wb), angle_deg = cv2.minAreaRect(points_xy.astype(np.float32))
    wa, wb = wa + pitch_m, wb + pitch_m  # pixel centres sit half a pixel inside the edges
    yaw = math.radians(angle_deg)
    yaw = (yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4
    fill = (points_xy.shape[0] if count is None else count) * pitch_m * pitch_m / max(wa * wb, 1e-12)
    return np.array([cx, cy]), wa, wb, yaw, fill


def circle_fill(points_xy: np.ndarray, pitch_m: float, count: int | None = None) -> float:
    """A point set's area / its minimum enclosing circle's (square 0.64, disc 1); count as for measure_rect."""
    _, radius = cv2.minEnclosingCircle(points_xy.astype(np.float32))
    radius += 0.5 * pitch_m
    return (points_xy.shape[0] if count is None else count) * pitch_m * pitch_m / max(math.pi * radius * radius, 1e-12)


def face_hull_xy(face: Face) -> np.ndarray:
    """What a face's minimum rectangle and circle are measured on: the convex hull of its points (the
    rectangle's and the circle's own first step, on a few dozen points instead of thousands). Without
    lens distortion the plane's homography maps the hull of the face's pixels, which is the hull of its
    outline (contour_px), onto the hull of its points; otherwise all points."""
    if face.plane_H is None or face.pixels_px is None or len(face.contour_px) < 3:
        return face.points_xy
    hull_px = cv2.convexHull(face.contour_px.astype(np.float32)).reshape(-1, 2).astype(np.float64)
    H_inv = inverse_homography(face.plane_H)
    xyw = hull_px @ H_inv[:, :2].T + H_inv[:, 2]
    return dehomogenise(xyw)


@dataclass(frozen=True)
class ClassifiedFace:
    size: str
    side_m: float
    yaw: float
    is_cube: bool
    centre_xy: np.ndarray
    stacks: list[tuple[float, tuple[str, ...]]]  # stack_candidates(top, size), best first


def classify_face(face: Face, cfg: PerceptionConfig, rect: tuple | None = None) -> ClassifiedFace:
    """Size, side, yaw, cube or not, centre and candidate stacks from the face's metric footprint and height.
    rect: measure_rect of its face_hull_xy if the caller has it."""
    pitch = math.sqrt(face.pixel_area_m2)
    hull = face_hull_xy(face)
    centre, wa, wb, yaw, fill = rect or measure_rect(hull, pitch, face.pixel_count)
    side = math.sqrt(wa * wb)
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m
    size = "large" if abs(side - large) < abs(side - small) else "small"
    edge = large if size == "large" else small
    stacks = stack_candidates(face.top_m, size, cfg)
    height_err = stacks[0][0]
    is_cube = (
        fill >= MIN_FILL
        and max(wa, wb) / max(min(wa, wb), 1e-9) <= MAX_ASPECT
        and abs(side - edge) <= SIZE_TOLERANCE * edge
        and height_err <= cfg.blocks.stack_height_tolerance_m
        and circle_fill(hull, pitch, face.pixel_count) <= MAX_CIRCLE_FILL
    )
    return ClassifiedFace(size, side, yaw, is_cube, face.points_xy.mean(axis=0) if is_cube else centre, stacks)


def fits_some_stack(top_m: float, cfg: PerceptionConfig) -> bool:
    """Whether a top at top_m is the height of some pile (with a large or a small block on top) within the
    stack tolerance: a face that is not can be no cube, nor can any part of it (a hand, pliers, a cable)."""
    tol = cfg.blocks.stack_height_tolerance_m
    return any(stack_candidates(top_m, size, cfg)[0][0] <= tol for size in ("large", "small"))


def face_part(face: Face, sel: np.ndarray) -> Face:
    """The part `sel` (bool over the face's points) of a face, with its own pixel centre and outline."""
    count = int(np.count_nonzero(sel))
    # np.compress: the rows boolean indexing gives, several times faster on (N, 2) arrays.
    if face.pixels_px is None or not count:
        return Face(face.points_xy.compress(sel, axis=0), face.top_m, face.contour_px, face.center_px, count, face.pixel_area_m2, face.plane_H)
    px = face.pixels_px.compress(sel, axis=0)
    hull = cv2.convexHull(px.astype(np.float32)).reshape(-1, 2).astype(np.float64)
    return Face(face.points_xy.compress(sel, axis=0), face.top_m, hull, px.mean(axis=0), count, face.pixel_area_m2, face.plane_H,
                 px, None if face.classes is None else face.classes[sel])


def face_colour(classes: np.ndarray | None, fallback: int) -> int:
    """The colour index + 1 most of a face's coloured pixels have (fallback when none is coloured)."""
    if classes is None:
        return fallback
    counts = np.bincount(classes, minlength=fallback + 1)
    counts[0] = 0
    return int(np.argmax(counts)) if counts.sum() else fallback


def split_touching(face: Face, cfg: PerceptionConfig) -> list[Face]:
    """Split a face holding several touching same-colour cubes by k-means on its points; [face] if no split fits."""
    return [part for part, _ in split_touching_classified(face, cfg)]


def split_touching_classified(face: Face, cfg: PerceptionConfig) -> list[tuple[Face, ClassifiedFace | None]]:
    """split_touching with each part's classify_face: [(face, None)] when no split fits."""
    area = face.pixel_count * face.pixel_area_m2
    candidates = []
    for edge in (cfg.blocks.large_size_m, cfg.blocks.small_size_m):
        n = int(round(area / (edge * edge)))
        if 2 <= n <= 6:
            candidates.append(n)
    # Every part keeps the face's height: at a height no pile has, no part is a cube (clutter: a hand,
    # pliers, cables), so no clustering is tried.
    if not candidates or not fits_some_stack(face.top_m, cfg):
        return [(face, None)]
    pts = face.points_xy.astype(np.float32)
    centred = pts - pts.mean(axis=0)
    axis = np.linalg.svd(centred, full_matrices=False)[2][0]  # the row of cubes lies along this axis
    along = centred @ axis
    pitch = math.sqrt(face.pixel_area_m2)
    # A face that fills its rectangle as cubes in a row do vouches for its parts' shape: a real depth's
    # holes and flying pixels fray one part's edge (0.76 of its rectangle beside a 0.91 twin, the pair 0.88).
    whole_fills: list[bool] = []  # measured when a part's own fill falls short

    def face_fills() -> bool:
        if not whole_fills:
            whole_fills.append(measure_rect(face_hull_xy(face), pitch, face.pixel_count)[4] >= SPLIT_MIN_FILL)
        return whole_fills[0]

    order = np.argsort(along)
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))  # each point's place along the axis (argsort's inverse permutation)
    sample = max(1, -(-len(pts) // SPLIT_SAMPLE_POINTS))
    large, small = cfg.blocks.large_size_m, cfg.blocks.small_size_m

    def classified_if_fits(part: Face) -> ClassifiedFace | None:
        rect = measure_rect(face_hull_xy(part), pitch, part.pixel_count)
        _, wa, wb, _, fill = rect
        side = math.sqrt(wa * wb)
        edge = large if abs(side - large) < abs(side - small) else small  # classify_face's size
        if not (max(abs(wa - edge), abs(wb - edge)) <= SPLIT_SIZE_TOLERANCE * edge and (fill >= SPLIT_MIN_FILL or face_fills())):
            return None
        classified = classify_face(part, cfg, rect)
        return classified if classified.is_cube else None

    def parts_if_all_fit(labels: np.ndarray) -> list[tuple[Face, ClassifiedFace]] | None:
        parts = []
        for k in range(n):
            part = face_part(face, labels == k)
            classified = classified_if_fits(part)
            if classified is None:
                return None
            parts.append((part, classified))
        return parts

    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-5)
    for n in candidates:
        # Deterministic start: n equal slices along the main axis, then k-means refines the split.
        labels = np.minimum((rank * n) // len(along), n - 1).astype(np.int32).reshape(-1, 1)
        if sample > 1:
            # k-means on an even subsample first, every point to its nearest centre: when those parts are
            # not all cubes (clutter: a hand, pliers), no split is; when they are, the full set's k-means
            # starts there and settles in a few iterations.
            _, _, centres = cv2.kmeans(np.ascontiguousarray(pts[::sample]), n, np.ascontiguousarray(labels[::sample]), criteria, 1,
                                       cv2.KMEANS_USE_INITIAL_LABELS)
            labels = _nearest_centre(pts, centres)
            if parts_if_all_fit(labels) is None:
                continue
            labels = labels.reshape(-1, 1)
        _, labels, _ = cv2.kmeans(pts, n, labels, criteria, 1, cv2.KMEANS_USE_INITIAL_LABELS)
        parts = parts_if_all_fit(labels.ravel())
        if parts is not None:
            return parts
    return [(face, None)]


def _nearest_centre(pts: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(N,) int32: each point's nearest centre (squared distance as the float32 points give it; the first of
    equals, as np.argmin), one centre at a time: cheaper than an argmin along the rows of an (N, k) array."""
    x, y = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
    best = labels = None
    for k, (cx, cy) in enumerate(centres.astype(np.float32)):
        dx, dy = x - cx, y - cy
        d2 = dx * dx + dy * dy
        if best is None:
            best, labels = d2, np.zeros(len(x), np.int32)
        else:
            closer = d2 < best
            labels[closer] = k
            np.minimum(best, d2, out=best)
    return labels


def runs_off_image(ys: np.ndarray, xs: np.ndarray, roi, cal: Calibration) -> bool:
    """True when a face (ROI rows ys, columns xs) reaches within BORDER_MARGIN_PX of the image's edge."""
    x0, y0 = roi[0], roi[1]
    m = BORDER_MARGIN_PX
    x_min, x_max, y_min, y_max = int(xs.min()), int(xs.max()), int(ys.min()), int(ys.max())
    return x_min + x0 <= m or y_min + y0 <= m or x_max + x0 >= cal.width - 1 - m or y_max + y0 >= cal.height - 1 - m


def classify_clipped(face: Face, ys: np.ndarray, xs: np.ndarray, roi, geo: BlockGeometry, cfg: PerceptionConfig) -> ClassifiedFace | None:
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
    return ClassifiedFace(size, fit.side_m, fit.yaw_rad, is_cube, fit.centre_xy, stacks)


def covered_by_stack(contour: np.ndarray, top_m: float, z: np.ndarray) -> bool:
    """True for a lower member of a stack: within the face's convex hull (contour in the coordinates
    of the ROI's heights z), a sizeable part stands well above the face (the block on top)."""
    hull = cv2.convexHull(contour)
    x, y, w, h = cv2.boundingRect(hull)  # the hull's pixels lie in its bounding box: counted there only
    inside = np.zeros((h, w), np.uint8)
    cv2.fillConvexPoly(inside, hull - np.array([x, y], hull.dtype), 1)
    above = np.count_nonzero((z[y : y + h, x : x + w] > top_m + 0.01) & inside.view(bool))
    return above > 0.15 * max(1, cv2.countNonZero(inside))
