"""Robot self-filter: which depth pixels belong to the robot, so perception ignores the arm and the
block it holds (the point-cloud pipelines' "robot self-filter").

From FK of the measured joints (ArmModel.joint_frames) the robot's body (armlab.devices.arm_body, the
shapes the simulation builds) becomes an inflated volume in the world frame: the links' capsules, the
base's housings, a box around the gripper and its open fingers, and a cube between the fingers for a
held block. A depth pixel is the robot when its 3-D point lies inside that volume;
a pixel with no depth reading is the robot when it lies inside the volume's projected silhouette.
A block on the board under a hovering gripper is not masked (its points are far below the gripper);
a block held in the gripper is. Only pixels inside each part's projected silhouette are back-projected,
every `pixel_step`-th one, so the mask costs about a millisecond per frame.

Frames as in DESIGN §3: world = board frame; T_world_camera maps camera (OpenCV) to world coordinates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from armlab.devices.arm_body import body_of
from armlab.vision.calibration import Calibration
from armlab.vision.config import SelfFilterConfig
from armlab.vision.geometry import as_points, invert_transform, normalized_rays, project_points_rt, projection_pose

_CELL_NEIGHBOURS = np.ones((3, 3), np.uint8)
_DEPTH_MARGIN_M = 0.001  # beyond a part's box in depth: far more than float32 rounding of a point's depth (~1e-7 m)
_UNIT_CUBE = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


@dataclass(frozen=True)
class RobotVolume:
    """The robot's inflated volume in the world frame (metres).

    capsule_ends_m (N, 2, 3) and capsule_radii_m (N,): points within the radius of a segment.
    box_poses (M, 4, 4) T_world_box and box_half_extents_m (M, 3): boxes centred on their pose's origin.
    """

    capsule_ends_m: np.ndarray
    capsule_radii_m: np.ndarray
    box_poses: np.ndarray
    box_half_extents_m: np.ndarray

    def contains(self, points_m: np.ndarray) -> np.ndarray:
        """(N,) bool: which world points (N, 3) lie inside the volume."""
        pts = as_points(points_m, 3, "points_m")
        inside = np.zeros(len(pts), bool)
        for (a, b), r in zip(self.capsule_ends_m, self.capsule_radii_m):
            inside |= _in_capsule(pts[:, 0], pts[:, 1], pts[:, 2], a, b, r)
        for T, half in zip(self.box_poses, self.box_half_extents_m):
            inside |= _in_box(pts[:, 0], pts[:, 1], pts[:, 2], T, half)
        return inside

    def hides(self, camera_position_m, points_m, samples: int = 32) -> bool:
        """True when the volume stands between the camera and any of the world points (N, 3): a point on
        some line of sight, sampled from the point up to the camera, lies inside it."""
        pts = as_points(points_m, 3, "points_m")
        t = np.linspace(0.0, 1.0, samples + 1)[1:, None, None]  # (S, 1, 1), the point itself left out
        along = pts[None] + t * (np.asarray(camera_position_m, dtype=float)[None, None] - pts[None])
        return bool(np.any(self.contains(along.reshape(-1, 3))))

    def hull_corners_m(self) -> np.ndarray:
        """(N + M, 8, 3): the corners of a box around each part (a capsule's is oriented along it).
        Each part's projected silhouette lies inside the convex hull of its corners' pixels."""
        capsules = _capsule_boxes(self.capsule_ends_m, self.capsule_radii_m)
        # corner k of box j: centre_j + R_j (unit_k * half_j)
        boxes = np.einsum("jab,jkb->jka", self.box_poses[:, :3, :3], _UNIT_CUBE[None] * self.box_half_extents_m[:, None, :])
        boxes += self.box_poses[:, None, :3, 3]
        return np.concatenate([capsules, boxes])

    def in_frame(self, T_to_from: np.ndarray) -> RobotVolume:
        """The same volume with every part moved by the rigid transform T (e.g. T_camera_world)."""
        R, t = T_to_from[:3, :3], T_to_from[:3, 3]
        return RobotVolume(self.capsule_ends_m @ R.T + t, self.capsule_radii_m, T_to_from @ self.box_poses, self.box_half_extents_m)


def _capsule_boxes(ends_m: np.ndarray, radii_m: np.ndarray) -> np.ndarray:
    """(N, 8, 3) corners of the box around each capsule (ends (N, 2, 3), radii (N,)), its long axis
    along the segment."""
    axis = ends_m[:, 1] - ends_m[:, 0]
    length = np.linalg.norm(axis, axis=1)
    u = np.where(length[:, None] > 1e-9, axis / np.maximum(length, 1e-9)[:, None], [0.0, 0.0, 1.0])
    helper = np.where(np.abs(u[:, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    v = _cross_rows(u, helper)
    v /= np.linalg.norm(v, axis=1)[:, None]
    w = _cross_rows(u, v)
    half = np.stack([0.5 * length + radii_m, radii_m, radii_m], axis=1)  # (N, 3) along u, v, w
    scaled = _UNIT_CUBE[None] * half[:, None, :]  # (N, 8, 3)
    centre = 0.5 * (ends_m[:, 0] + ends_m[:, 1])
    return centre[:, None] + scaled[..., :1] * u[:, None] + scaled[..., 1:2] * v[:, None] + scaled[..., 2:] * w[:, None]


def _cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """np.cross of (N, 3) rows, by the same products and differences (bitwise the same), without
    np.cross's generality: a tenth of its time on a handful of rows."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def _in_capsule(X, Y, Z, a, b, radius_m: float) -> np.ndarray:
    """Which points (coordinate arrays of any one shape) lie within radius_m of the segment a-b."""
    ab = b - a
    denom = float(ab @ ab)
    dx, dy, dz = X - np.float32(a[0]), Y - np.float32(a[1]), Z - np.float32(a[2])
    if denom > 1e-18:
        t = (dx * np.float32(ab[0]) + dy * np.float32(ab[1]) + dz * np.float32(ab[2])) * np.float32(1.0 / denom)
        np.maximum(t, np.float32(0.0), out=t)  # np.clip's values, without its overhead
        np.minimum(t, np.float32(1.0), out=t)
        dx -= t * np.float32(ab[0])
        dy -= t * np.float32(ab[1])
        dz -= t * np.float32(ab[2])
    return dx * dx + dy * dy + dz * dz <= np.float32(radius_m * radius_m)


def _in_box(X, Y, Z, T_frame_box: np.ndarray, half_m: np.ndarray) -> np.ndarray:
    """Which points lie inside the box centred at T_frame_box's origin with half extents half_m."""
    R, c = T_frame_box[:3, :3].astype(np.float32), T_frame_box[:3, 3].astype(np.float32)
    dx, dy, dz = X - c[0], Y - c[1], Z - c[2]
    inside = None
    for k in range(3):
        local = dx * R[0, k] + dy * R[1, k] + dz * R[2, k]
        within = np.abs(local) <= np.float32(half_m[k])
        inside = within if inside is None else inside & within
    return inside


def robot_volume(model, joints_rad, cfg: SelfFilterConfig, held_block_edge_m: float | None = None) -> RobotVolume:
    """The robot's inflated volume at joints_rad (dof,) of an armlab.kinematics ArmModel: its body
    (armlab.devices.arm_body, the shapes the simulation builds), grown.

    Capsules: the links' capsules grown by cfg.margin_m; boxes grown by cfg.box_margin_m: the base's housings, the
    box around the gripper's parts in the tool frame (fingers open: the joints do not say how far); and a held block
    of held_block_edge_m (None: cfg's; 0: none), spanning from half an edge behind the gripper point to a full edge
    beyond it, grown by cfg.held_block_margin_m.
    ValueError for malformed joints or a negative or non-finite edge.
    """
    edge = cfg.held_block_edge_m if held_block_edge_m is None else held_block_edge_m
    if not (isinstance(edge, (int, float)) and math.isfinite(edge) and 0.0 <= edge < 0.5):
        raise ValueError(f"held_block_edge_m must be a finite number in [0, 0.5) m, got {held_block_edge_m!r}")
    body = body_of(model)
    tool = body.tool_frame
    placed = body.place(model, joints_rad, held_edge_m=edge if edge > 0.0 else None)
    capsules = placed.indices("capsule")
    solids = [k for k, part in enumerate(placed.parts) if part.shape != "capsule" and part.frame != tool]
    ends, radii = placed.segments(capsules)
    poses, halves = placed.boxes(solids)
    T_tool_box, tool_half = body.tool_bounds()
    tool_pose = np.asarray(model.joint_frames(joints_rad))[-1] @ T_tool_box
    box_poses, box_halves = [*poses[0], tool_pose], [*(halves + cfg.box_margin_m), tool_half + cfg.box_margin_m]
    if edge > 0.0:
        (k,) = [k for k, part in enumerate(placed.parts) if part.name == "held block"]
        held_poses, held_half = placed.boxes([k])
        box_poses.append(held_poses[0, 0])
        box_halves.append(held_half[0] + cfg.held_block_margin_m)
    return RobotVolume(
        capsule_ends_m=ends[0],
        capsule_radii_m=radii + cfg.margin_m,
        box_poses=np.array(box_poses),
        box_half_extents_m=np.array(box_halves, dtype=float),
    )


class _RayGrid:
    """Undistorted normalised image coordinates (x, y) of every step-th pixel, for one calibration."""

    def __init__(self, cal: Calibration, step: int) -> None:
        self.calibration = cal
        self.step = step
        us = np.arange(0, cal.width, step, dtype=np.float64)
        vs = np.arange(0, cal.height, step, dtype=np.float64)
        if np.any(np.asarray(cal.dist) != 0):
            grid = np.stack(np.meshgrid(us, vs), axis=-1).reshape(-1, 2)
            rays = normalized_rays(grid, cal.K, cal.dist)
            self.x = rays[:, 0].reshape(len(vs), len(us)).astype(np.float32)
            self.y = rays[:, 1].reshape(len(vs), len(us)).astype(np.float32)
            self.x_of_column = self.y_of_row = None
        else:  # a pinhole: x depends on the column only, y on the row
            xn = ((us - cal.K[0, 2]) / cal.K[0, 0]).astype(np.float32)
            yn = ((vs - cal.K[1, 2]) / cal.K[1, 1]).astype(np.float32)
            self.x, self.y = np.broadcast_to(xn[None, :], (len(vs), len(us))), np.broadcast_to(yn[:, None], (len(vs), len(us)))
            self.x_of_column, self.y_of_row = xn, yn
        self.T_camera_world = invert_transform(cal.T_world_depth)  # depth points are tested: the depth model
        self.projection = projection_pose(cal.T_world_camera)  # silhouettes are drawn in the colour image


def robot_mask(depth_mm: np.ndarray, cal: Calibration, volume: RobotVolume, pixel_step: int = 2, rays: _RayGrid | None = None) -> np.ndarray:
    """(H, W) bool: the robot's pixels (robot_mask_cells' mask)."""
    return robot_mask_cells(depth_mm, cal, volume, pixel_step, rays)[0]


def robot_mask_cells(depth_mm: np.ndarray, cal: Calibration, volume: RobotVolume, pixel_step: int = 2,
                     rays: _RayGrid | None = None) -> tuple[np.ndarray, np.ndarray]:
    """((H, W) bool mask, (H', W') uint8 cells): the mask holds pixels whose depth point lies inside the volume, or that have no depth reading
    and lie inside the volume's projected silhouette. depth_mm: (H, W) uint16 mm along the optical
    axis, 0 = none. Every pixel_step-th pixel is tested and fills its pixel_step x pixel_step cell
    (with pixel_step > 1 the cells next to a robot cell are marked too: at most pixel_step pixels more).
    rays: a cached _RayGrid for (cal, pixel_step), if the caller keeps one. cells: 1 where a pixel_step x pixel_step
    cell is the robot's: the mask is the cells upscaled pixel_step times (cropped to the image), so a caller may read
    the mask at a coarser step, or test a window for robot pixels, on the cells (see blocks.detect_blocks)."""
    h, w = cal.height, cal.width
    if not isinstance(depth_mm, np.ndarray) or depth_mm.shape != (h, w) or depth_mm.dtype != np.uint16:
        raise ValueError(f"depth must be a uint16 (H, W) = ({h}, {w}) image in mm, got {getattr(depth_mm, 'shape', None)}")
    step = int(pixel_step)
    if step < 1:
        raise ValueError(f"pixel_step must be >= 1, got {pixel_step!r}")
    if rays is None or rays.calibration is not cal or rays.step != step:
        rays = _RayGrid(cal, step)
    grid_h, grid_w = rays.x.shape
    mask = np.zeros((h, w), bool)
    # The parts' robot cells on the sample grid, filled in at full resolution once (an upscale by a whole factor
    # maps each pixel to its cell, so this is the union of the parts' own upscaled cells).
    cells = np.zeros((grid_h, grid_w), np.uint8)
    span = [grid_w, grid_h, 0, 0]  # the grid window holding every part's cells
    local = volume.in_frame(rays.T_camera_world)
    corners_world = volume.hull_corners_m()
    corners_camera = corners_world @ rays.T_camera_world[:3, :3].T + rays.T_camera_world[:3, 3]
    grid_pts = project_points_rt(rays.projection, cal.K, cal.dist, corners_world.reshape(-1, 3)).reshape(-1, 8, 2) / step
    # Every part's window on the sample grid and its hull's corners in the window (1/16 px), all parts at once.
    # A part reaching behind the camera (a nonsense calibration or pose) has no silhouette: it is skipped.
    in_front = np.all(corners_camera[..., 2] > 0.01, axis=1).tolist()
    # Each part lies within its box, so a point can be inside it only at a depth within its box corners' (plus a
    # millimetre for rounding): only those points are tested (the others' answer is known: outside).
    depth_lows = (corners_camera[..., 2].min(axis=1) - _DEPTH_MARGIN_M).tolist()
    depth_highs = (corners_camera[..., 2].max(axis=1) + _DEPTH_MARGIN_M).tolist()
    lows = np.maximum(np.floor(grid_pts.min(axis=1)).astype(int), 0)
    highs = np.minimum(np.ceil(grid_pts.max(axis=1)).astype(int) + 1, (grid_w, grid_h))
    corners_fixed = np.round((grid_pts - lows[:, None, :]) * 16).astype(np.int32)
    n_capsules = len(local.capsule_radii_m)
    for index, ((x0, y0), (x1, y1)) in enumerate(zip(lows.tolist(), highs.tolist())):
        if not in_front[index] or x0 >= x1 or y0 >= y1:
            continue  # behind the camera, or outside the image
        silhouette = np.zeros((y1 - y0, x1 - x0), np.uint8)
        cv2.fillConvexPoly(silhouette, cv2.convexHull(corners_fixed[index]), 1, lineType=cv2.LINE_8, shift=4)
        inside = silhouette.view(bool)
        d_mm = depth_mm[y0 * step : y1 * step : step, x0 * step : x1 * step : step][inside]  # a part's points project inside it
        Z = d_mm.astype(np.float32) * np.float32(0.001)
        hit_inside = d_mm == 0
        near = np.flatnonzero((Z >= depth_lows[index]) & (Z <= depth_highs[index]))
        if len(near):
            Z = Z.take(near)
            if rays.x_of_column is not None:  # a pinhole: the near samples' rays from their columns and rows
                rows, columns = np.divmod(np.flatnonzero(inside).take(near), x1 - x0)
                X, Y = Z * rays.x_of_column.take(columns + x0), Z * rays.y_of_row.take(rows + y0)
            else:
                X, Y = Z * rays.x[y0:y1, x0:x1][inside].take(near), Z * rays.y[y0:y1, x0:x1][inside].take(near)
            if index < n_capsules:
                (a, b), r = local.capsule_ends_m[index], local.capsule_radii_m[index]
                hit_inside[near] |= _in_capsule(X, Y, Z, a, b, r)
            else:
                k = index - n_capsules
                hit_inside[near] |= _in_box(X, Y, Z, local.box_poses[k], local.box_half_extents_m[k])
        hit = np.zeros(inside.shape, bool)
        hit[inside] = hit_inside
        hit = hit.view(np.uint8)
        if step > 1:  # a sample stands for its cell; grown by one cell so the robot's edge cells are covered
            hit = cv2.dilate(hit, _CELL_NEIGHBOURS)
        cells[y0:y1, x0:x1] |= hit
        span = [min(span[0], x0), min(span[1], y0), max(span[2], x1), max(span[3], y1)]
    x0, y0, x1, y1 = span
    if x1 > x0 and y1 > y0:
        hit = cells[y0:y1, x0:x1]
        if step > 1:
            hit = cv2.resize(hit, ((x1 - x0) * step, (y1 - y0) * step), interpolation=cv2.INTER_NEAREST)
        full = mask[y0 * step : y1 * step, x0 * step : x1 * step]
        full |= hit[: full.shape[0], : full.shape[1]].view(bool)
    return mask, cells


class RobotSelfFilter:
    """The self-filter for one arm model and config; caches its per-calibration ray grid (one per
    perception thread: not thread-safe)."""

    def __init__(self, model, cfg: SelfFilterConfig) -> None:
        self.model = model
        self.cfg = cfg
        self._rays: _RayGrid | None = None

    def volume(self, joints_rad, held_block_edge_m: float | None = None) -> RobotVolume:
        """robot_volume for this arm and config."""
        return robot_volume(self.model, joints_rad, self.cfg, held_block_edge_m)

    def mask(self, depth_mm: np.ndarray, cal: Calibration, joints_rad, held_block_edge_m: float | None = None) -> np.ndarray:
        """(H, W) bool robot mask of a depth image taken with the arm at joints_rad (see robot_mask)."""
        return self.mask_and_cells(depth_mm, cal, joints_rad, held_block_edge_m)[0]

    def mask_and_cells(self, depth_mm: np.ndarray, cal: Calibration, joints_rad,
                       held_block_edge_m: float | None = None) -> tuple[np.ndarray, tuple[np.ndarray, int]]:
        """(mask, (cells, pixel_step)): mask and robot_mask_cells' cells, with the step they are upscaled by."""
        step = self.cfg.pixel_step
        if self._rays is None or self._rays.calibration is not cal or self._rays.step != step:
            self._rays = _RayGrid(cal, step)
        mask, cells = robot_mask_cells(depth_mm, cal, self.volume(joints_rad, held_block_edge_m), step, self._rays)
        return mask, (cells, step)
