"""Block detection from colour + depth: colour class, size class from the metric footprint, top-face
centre and yaw in the world, stack level from height, touching same-colour blocks split, arm
occlusion flagged, distractors rejected, and tag-topped blocks identified. A top face the image's edge
cuts (a tall stack's top leaving the camera's view) is measured from the edges that show
(clipped_face.py), or flagged occluded when they do not fix it.

Speed: colour and height are computed at quarter resolution to find candidates; each candidate's top
face is then measured on a full-resolution region of interest.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial

import cv2
import numpy as np

from armlab.vision.block import Block
from armlab.vision.block_geometry import STEP, BlockGeometry, frame_geometry, roi_heights
from armlab.vision.block_pixels import (
    NEAR_COLOUR_KERNEL,
    any_ignored,
    colour_classes,
    components,
    frozen_class_table,
    pixels_at,
    pixels_of,
    seeded_blob,
)
from armlab.vision.block_tags import face_looks_tagged, with_tag
from armlab.vision.calibration import Calibration
from armlab.vision.colors import MAX_FACE_SAMPLES, BoardGrey, ColorModel, frame_clip_levels_rgb
from armlab.vision.config import PerceptionConfig
from armlab.vision.distractors import (
    dark_and_colourless,
    not_cube,
    part_of_larger_surface,
)
from armlab.vision.face_shape import (
    SIZE_TOLERANCE,
    ClassifiedFace,
    Face,
    classify_clipped,
    classify_face,
    covered_by_stack,
    face_colour,
    quantile,
    runs_off_image,
    split_touching_classified,
)
from armlab.vision.geometry import PlaneCamera, height_map_m
from armlab.vision.stacks import choose_stack, stack_candidates, stack_from_height
from armlab.vision.tags import check_color_image, make_detector

__all__ = ["Block", "BlockGeometry", "detect_blocks", "stack_from_height", "stack_candidates"]


def _closer_than_m(a: np.ndarray, b: np.ndarray, limit_m: float) -> bool:
    """Whether points a and b are closer than limit_m in x and y."""
    return math.hypot(float(a[0]) - float(b[0]), float(a[1]) - float(b[1])) < limit_m


MAX_GROWTH = 1.7
EDGE_GROW_PX = 3  # a real depth image rounds a top's edges over ~3 px (L515, ROB 550 frames): the face regains them from colour
_EDGE_GROW_KERNEL = np.ones((2 * EDGE_GROW_PX + 1, 2 * EDGE_GROW_PX + 1), np.uint8)


def _top_face_in_roi(
    z: np.ndarray, band: np.ndarray, keep: np.ndarray, tol_m: float, seed: np.ndarray | None = None,
    grow: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float] | None:
    """ROI pixels (flat indices, rows, columns), contour (ROI coordinates) and median height of the flat
    face in the band of heights z within tol_m of the guess (band), among the pixels to keep.

    Two passes: the loose band finds the face, a tight band around its median keeps only the face
    (side-face pixels just below the top edge would bias the footprint toward the camera).
    """
    blob = seeded_blob(band & keep, seed)
    if blob is None:
        return None
    face_m = quantile(z.ravel().compress(blob.ravel().view(bool)), 0.5)
    blob &= (np.abs(z - face_m) < 0.5 * tol_m).view(np.uint8)
    blob_px = cv2.countNonZero(blob)
    if not blob_px:
        return None
    if grow is not None:  # the edge pixels depth smoothing pulled below the band, where colour says top
        grown = blob | (cv2.dilate(blob, _EDGE_GROW_KERNEL) & grow.view(np.uint8))
        # A ring of EDGE_GROW_PX around a face: at most (29/23)^2 ~ 1.6x a small cube's top at 1 m. More is a
        # sliver (a lower stack member's side) growing into a face, not an edge regained.
        if cv2.countNonZero(grown) <= MAX_GROWTH * blob_px:
            blob = grown
    contours, _ = cv2.findContours(blob, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    contour = max(contours, key=cv2.contourArea)
    # Holes inside the outline (a highlight, a knot in the wood, a depth dropout) are the face too.
    filled = np.zeros_like(blob)
    cv2.drawContours(filled, [contour], -1, 1, thickness=cv2.FILLED)
    flat, ys, xs = pixels_of(filled)
    zs = z.take(flat)
    zs = zs[np.isfinite(zs)]
    return flat, ys, xs, contour, quantile(zs, 0.5) if zs.size else face_m


def _face_from_pixels(ys: np.ndarray, xs: np.ndarray, roi, contour: np.ndarray, top_m: float, camera: PlaneCamera) -> Face:
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
    return Face(world_xy[:-3], top_m, contour_px.astype(np.float64), np.array([u, v]), n, pixel_area, H, pixels[:n])


def detect_blocks(
    color_bgr: np.ndarray,
    depth_mm: np.ndarray,
    cal: Calibration,
    cfg: PerceptionConfig,
    tag_detector: cv2.aruco.ArucoDetector | None = None,
    geometry: BlockGeometry | None = None,
    ignore_mask: np.ndarray | None = None,
    color_model: ColorModel | None = None,
    ignore_cells: tuple[np.ndarray, int] | None = None,
) -> list[Block]:
    """Blocks (top of each stack) and flagged non-cubes on the board, sorted by y then x.

    tag_detector: a prebuilt detector for the block-tag dictionary (saves its construction per frame).
    geometry: BlockGeometry(cal), if the caller keeps one per calibration (saves its computation per frame).
    ignore_mask: (H, W) bool pixels that are not the scene (the robot self-filter's mask): no face is
    built from them, and a block partly hidden under them, or partly inside them, is flagged occluded.
    color_model: names each face's colour from its pixels and the board's grey around it (default: the
    config's, armlab.vision.colors); the hue classes only find candidate pixels.
    ignore_cells: (cells, step) that ignore_mask is the upscale of (self_filter.robot_mask_cells), if the caller
    has them: the mask is then read at quarter resolution, and regions tested for robot pixels, on them (cheaper).
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
    # The robot is not left out of the board-plane fit: it stands far above the fit's window anyway, and
    # so the heights of everything else do not depend on whether the arm's joints are known.
    geo = frame_geometry(geo, depth_small, cfg)
    z_small = height_map_m(depth_small, geo.small_K, geo.height_row, coefficients=geo.small_coefficients)
    raised = (z_small > bc.min_height_m) & (z_small < bc.max_height_m)
    names = list(cfg.blocks.colors)
    # Every step-th pixel: nearest-neighbour resizing by an integer factor picks exactly those, and
    # far faster than copying the strided view.
    small_bgr = cv2.resize(color_bgr, geo.small_shape[::-1], interpolation=cv2.INTER_NEAREST)
    hsv_small = cv2.cvtColor(small_bgr, cv2.COLOR_BGR2HSV)
    table = frozen_class_table(tuple(cfg.blocks.colors[name] for name in names))
    classes = colour_classes(hsv_small, cfg, table)
    colourless = classes == 0  # e.g. the white and black of a tag on a block's top
    classes *= raised  # no colour class where nothing is raised (the board's own colours)
    # The board's own brightness (median value of its pixels in this frame): the scale a block's
    # colourfulness is judged on (lighting and exposure change both alike).
    board_px = np.abs(z_small[::2, ::2]) < cfg.board_plane.inlier_m  # NaN (no depth) compares False, quietly
    board_value = quantile(hsv_small[::2, ::2, 2][board_px], 0.5) if np.count_nonzero(board_px) >= 20 else 255.0
    z_cover = z_small  # what may hide part of a face: what stands above it, and the robot
    cells = ignore_cells if ignore_mask is not None and ignore_cells is not None and step % ignore_cells[1] == 0 else None
    if ignore_mask is None:
        ignored_small = None
    elif cells is not None:  # full[step * i, step * j] is cells[step * i // s, step * j // s]
        ignored_small = np.ascontiguousarray(cells[0][:: step // cells[1], :: step // cells[1]]).view(bool)
    else:
        ignored_small = np.ascontiguousarray(ignore_mask[::step, ::step])  # contiguous: cheaper masking
    if ignored_small is not None:  # the robot: neither colour nor a tag's white
        classes[ignored_small] = 0
        colourless[ignored_small] = False
        z_cover = z_small.copy()
        z_cover[ignored_small] = np.inf
    board_small = (z_small < bc.min_height_m) & (z_small > -0.03)  # at the board (or its depth offset): the colour model's grey
    board_small &= geo.board_region(cfg.board.x_range_m, cfg.board.y_range_m)
    if ignored_small is not None:
        board_small &= ~ignored_small
    colour_of = _face_colour(color_model or ColorModel.from_config(cfg), BoardGrey(small_bgr, board_small, scale=step),
                             frame_clip_levels_rgb(small_bgr))
    coloured = (classes > 0).astype(np.uint8)
    # A tag on a block's top is white and black: bridge its white (next to colour, never the dark arm)
    # so the thin coloured ring around it stays one candidate at this resolution.
    candidates = coloured.copy()
    # Near colour is within the colour's bounding box grown by the kernel's reach: worked out there only.
    cx, cy, cw, ch = cv2.boundingRect(coloured)
    if cw and ch:
        win = np.s_[max(cy - 3, 0) : cy + ch + 3, max(cx - 3, 0) : cx + cw + 3]
        near_colour = cv2.dilate(coloured[win], NEAR_COLOUR_KERNEL).view(bool)
        candidates[win] |= (raised[win] & colourless[win] & near_colour & (hsv_small[win][..., 2] >= 150)).view(np.uint8)
    n, labels, stats_list = components(candidates)
    labels_x, labels_y = stats_list[0][:2]  # the labels' window in the image (components)
    pixel_m = abs(float(cal.T_world_camera[2, 3])) / cal.K[0, 0] * step  # board-level pixel size, roughly
    min_face_px = 0.25 * bc.small_size_m**2 / pixel_m**2
    detector = tag_detector
    blocks: list[Block] = []
    for k in range(1, n):
        x, y, bw, bh, area = stats_list[k]
        if area < 4:
            continue
        sel = labels[y - labels_y : y - labels_y + bh, x - labels_x : x - labels_x + bw] == k
        flat, ys, xs = pixels_of(sel)
        comp_classes = classes[y : y + bh, x : x + bw].ravel().take(flat)
        comp_z = z_small[y : y + bh, x : x + bw].ravel().take(flat)
        counts = np.bincount(comp_classes, minlength=len(names) + 1)
        roi = (max(0, x * step - 8), max(0, y * step - 8), min(w, (x + bw) * step + 8), min(h, (y + bh) * step + 8))
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
            top_xs, top_ys = xs[layer], ys[layer]
            # The centroid from integer sums (exact: as np.mean's), the bounding box grown by a pixel.
            centroid = np.array([top_xs.sum() / len(top_xs), top_ys.sum() / len(top_ys)])
            tops[int(ci)] = (top_m, centroid, np.array([top_xs.min() - 1, top_ys.min() - 1, top_xs.max() + 1, top_ys.max() + 1]))
        region = None  # the ROI's colour and heights, shared by the colours of this component
        made: list[Block] = []  # this component's blocks: a face holds every colour on it
        for ci, (top_m, centroid, box) in tops.items():
            if any(
                other_top > top_m + 0.01 and box[0] <= centre[0] <= box[2] and box[1] <= centre[1] <= box[3]
                for cj, (other_top, centre, _) in tops.items() if cj != ci
            ):
                continue  # a lower member of a stack: the block on top sits inside its footprint
            u, v = float(centroid[0] + x) * step, float(centroid[1] + y) * step
            if any(abs(b.height_m - top_m) < bc.top_face_tolerance_m
                   and cv2.pointPolygonTest(b.contour_px.astype(np.float32).reshape(-1, 1, 2), (u, v), False) >= 0 for b in made):
                continue  # this colour's top is part of a face already measured (a second hue on it)
            region = region or _Region(color_bgr, depth_mm, geo, cfg, roi, table, ignore_mask, cells)
            region.board_value = board_value
            region.coloured_small = coloured
            for block, looks_tagged in _blocks_from_region(color_bgr, geo, cfg, region, top_m, names, ci, z_cover, step, colour_of):
                made.append(block)
                if any(_closer_than_m(block.position_m, b.position_m, 0.015) and block.height_m <= b.height_m + 0.01
                       for b in blocks):
                    continue  # found already (from another colour on it)
                if block.aruco_id is None and block.is_cube and looks_tagged():  # not on the arm or a distractor
                    detector = detector or make_detector(cfg.tags.block_tag_dictionary)
                    block = with_tag(block, color_bgr, roi, detector, cfg)
                twins = [b for b in blocks if _closer_than_m(block.position_m, b.position_m, 0.015)]
                if not twins:
                    blocks.append(block)
                elif all(block.height_m > b.height_m + 0.01 for b in twins):  # keep a stack's top only
                    blocks = [b for b in blocks if not any(b is twin for twin in twins)] + [block]
    # Off the board (the workcell's rectangle) is not the scene: walls, the table, boxes at the image's edge.
    (bx0, bx1), (by0, by1) = cfg.board.x_range_m, cfg.board.y_range_m
    blocks = [b for b in blocks if bx0 <= b.position_m[0] <= bx1 and by0 <= b.position_m[1] <= by1]
    return sorted(blocks, key=lambda b: (round(float(b.position_m[1]), 3), float(b.position_m[0])))


class _Region:
    """A region of interest at full resolution: its HSV image, colour classes and world heights."""

    def __init__(self, color_bgr: np.ndarray, depth_mm: np.ndarray, geo: BlockGeometry, cfg: PerceptionConfig, roi, table: np.ndarray,
                 ignore_mask: np.ndarray | None = None, ignore_cells: tuple[np.ndarray, int] | None = None) -> None:
        x0, y0, x1, y1 = roi
        self.roi = roi
        self.board_value = 255.0
        self.coloured_small: np.ndarray | None = None  # the frame's block-coloured pixels at STEP
        self.hsv = cv2.cvtColor(color_bgr[y0:y1, x0:x1], cv2.COLOR_BGR2HSV)
        self.classes = colour_classes(self.hsv, cfg, table)
        self.colourless = self.classes == 0
        self.z = roi_heights(depth_mm, geo, roi)
        ignored = None if ignore_mask is None or not any_ignored(ignore_mask, ignore_cells, roi) else ignore_mask[y0:y1, x0:x1]
        if ignored is not None:  # the robot: no height, so it neither forms a face nor covers one
            self.classes[ignored] = 0
            self.colourless[ignored] = False
            self.z[ignored] = np.nan
        self.coloured = self.classes > 0
        self.value = cv2.extractChannel(self.hsv, 2)  # HSV value, contiguous


def _face_colour(model: ColorModel, grey: BoardGrey, clip_from_rgb: np.ndarray):
    """colour_of(face_bgr, centre_px) -> ColorReading: the model's reading against the board's grey near
    the face, channels clipped from the frame's clip_from_rgb (frame_clip_levels_rgb)."""
    return lambda face_bgr, centre_px: model.classify(face_bgr, grey.near(centre_px), clip_from_rgb)


def _blocks_from_region(color_bgr, geo: BlockGeometry, cfg, region: _Region, top_m, names, ci, z_small, step,
                        colour_of=None) -> list[tuple[Block, Callable[[], bool]]]:
    """The top face at about top_m in the ROI that holds this colour's top pixels, as blocks, each with
    a call saying whether its face looks tagged (face_looks_tagged; asked only of cubes without a tag id).
    The face is every block-coloured (or colourless, e.g. a tag) pixel at that height connected to them: a cube whose top reads as two hues
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
    value = region.value
    keep = region.colourless.copy()
    for cj in np.flatnonzero(np.bincount(classes[band], minlength=1)[1:]) + 1:
        colour, top = (mine, seed) if cj == ci else (classes == cj, None)
        top = (colour & band) if top is None else top
        if np.count_nonzero(top) >= 10:
            keep |= colour & (value >= 0.7 * quantile(value[top], 0.95))
        else:
            keep |= colour
    # Bright block colour no lower than half a small cube under the top (and not above it: the
    # block on top of a lower stack member): the top's rounded edge. (NaN heights compare False, quietly.)
    grow = keep & region.coloured & (z > top_m - 0.5 * cfg.blocks.small_size_m) & (z < top_m + tol)
    found = _top_face_in_roi(z, band, keep, tol, seed, grow)
    if found is None:
        return []
    flat, ys, xs, contour, face_m = found
    face_classes = classes.ravel().take(flat)
    if np.count_nonzero(face_classes) / len(ys) < 0.15:
        return []  # the face is mostly another object's colourless top
    face = _face_from_pixels(ys, xs, roi, contour, face_m, geo.camera)
    face.classes = face_classes
    small = cfg.blocks.small_size_m
    if face.pixel_count * face.pixel_area_m2 < 0.3 * small * small:
        return []  # a sliver: the edge of a lower stack member or noise
    if covered_by_stack(contour, face_m, z):
        return []  # a lower member of a stack: something sits on its centre

    def part_of_more() -> bool:  # only asked about faces that would otherwise be cubes
        return (dark_and_colourless(hsv.reshape(-1, 3).take(flat, axis=0), face_classes, region.board_value)
                or part_of_larger_surface(face, z_small, step, tol, region.coloured_small))

    def block_of(f: Face, classified: ClassifiedFace | None = None, out_of_view: bool = False) -> Block:
        if colour_of is None or f.pixels_px is None:
            return _make_block(f, names[face_colour(f.classes, ci) - 1], geo.camera, cfg, z_small, step, z, classified, out_of_view)
        px = f.pixels_px
        if f.classes is not None and np.count_nonzero(f.classes) >= 10:
            px = px.compress(f.classes > 0, axis=0)
        if len(px) > MAX_FACE_SAMPLES:  # the pixels face_median_rgb would keep, before gathering them
            px = px[:: len(px) // MAX_FACE_SAMPLES]
        px = px.astype(np.intp)
        reading = colour_of(pixels_at(color_bgr, px), f.center_px)
        return _make_block(f, reading.name, geo.camera, cfg, z_small, step, z, classified, out_of_view, reading.measured_lab)

    if runs_off_image(ys, xs, roi, geo.calibration):
        # A tall stack's top partly out of view: the square from the edges that show, else flagged.
        # No tag lookup: a tag on a cut face is likely cut too.
        clipped = classify_clipped(face, ys, xs, roi, geo, cfg)
        if clipped is None or not clipped.is_cube or part_of_more():
            return [(not_cube(block_of(face, clipped, out_of_view=True)), _never)]
        return [(block_of(face, clipped), _never)]
    classified = classify_face(face, cfg)
    if classified.is_cube:
        blocks = [block_of(face, classified)]
    else:
        blocks = [block_of(part, part_classified or classified) for part, part_classified in split_touching_classified(face, cfg)]
    if any(b.is_cube for b in blocks) and part_of_more():
        blocks = [not_cube(b) for b in blocks]
    return [(block, partial(face_looks_tagged, color_bgr, block, roi, hsv, region.board_value)) for block in blocks]


def _never() -> bool:
    """A face that never looks tagged (cut by the image's edge: a tag on it is likely cut too)."""
    return False


def _make_block(face: Face, color: str, camera: PlaneCamera, cfg, z_small, step, z_roi=None, classified: ClassifiedFace | None = None,
                out_of_view: bool = False, color_lab: tuple[float, float, float] | None = None) -> Block:
    """The block of a face (classified: its classify_face or classify_clipped, if at hand).
    out_of_view: part of the face is outside the image and its square is not known: flagged occluded.
    color_lab: the face's measured colour, if the colour model read it."""
    c = classified or classify_face(face, cfg)
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
        color_lab=color_lab,
    )


def _is_occluded(face: Face, centre_xy, yaw: float, size: str, camera: PlaneCamera, cfg: PerceptionConfig, z_small: np.ndarray, step: int) -> bool:
    """True when something well above the face (the arm) covers part of where the cube's top should be:
    the expected square, drawn around the measured centre, holds readings 15 mm or more above the face."""
    edge = cfg.blocks.large_size_m if size == "large" else cfg.blocks.small_size_m
    half = 0.5 * edge
    c, s = math.cos(yaw), math.sin(yaw)
    cx, cy = float(centre_xy[0]), float(centre_xy[1])  # plain floats: the same sums, cheaper than numpy scalars
    square = np.array([[cx + c * a - s * b, cy + s * a + c * b] for a, b in ((-half, -half), (half, -half), (half, half), (-half, half))])
    poly = camera.project(square, face.top_m, face.plane_H) / step
    us, vs = poly[:, 0].tolist(), poly[:, 1].tolist()
    x0, y0 = max(math.floor(min(us)) - 1, 0), max(math.floor(min(vs)) - 1, 0)
    x1, y1 = math.ceil(max(us)) + 2, math.ceil(max(vs)) + 2
    window = z_small[y0:y1, x0:x1]
    if window.size == 0:
        return False
    inside = np.zeros(window.shape, np.uint8)
    cv2.fillConvexPoly(inside, np.round(poly - [x0, y0]).astype(np.int32), 1)
    above = np.count_nonzero((window > face.top_m + 0.008) & inside.view(bool))
    # At least 3 samples: a small cube's square holds ~30, and one or two can be a depth dropout the
    # robot mask claims at its edge.
    return above > max(2, 0.05 * cv2.countNonZero(inside))
