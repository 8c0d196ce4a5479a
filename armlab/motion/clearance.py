"""Clearance between the arm and known objects: the arm's body against boxes around objects.

The arm is its body (armlab.devices.arm_body, the shapes the simulation builds): the links' capsules and the
gripper's (or cup's) parts, kept a margin away; objects (blocks, stacks, distractors) are axis-aligned boxes from
the board up to their top. Boxes around objects are enough (issue 8): a plan that keeps the body outside every
grown box does not touch them. The self-check (self_collision) still samples points along the links. Pure: no devices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.devices.arm_body import body_of

LINK_POINTS_PER_SEGMENT = 4


@dataclass(frozen=True)
class ObstacleBox:
    """An axis-aligned box: centre (x, y), half extents in x and y, from z = 0 up to top_z_m."""

    name: str
    center_xy_m: tuple[float, float]
    half_xy_m: tuple[float, float]
    top_z_m: float


def box_around(name: str, center_xy_m, radius_m: float, top_z_m: float) -> ObstacleBox:
    """A square box of half-width radius_m around an object's centre (any yaw fits inside)."""
    return ObstacleBox(name, (float(center_xy_m[0]), float(center_xy_m[1])), (radius_m, radius_m), float(top_z_m))


def arm_points_m(model, positions_rad: np.ndarray, finger_length_m: float, held_edge_m: float | None) -> np.ndarray:
    """World points (N, P, 3) along the arm's links for each joint vector, plus the finger tips and,
    when a block is held, its bottom corners' centre (the lowest thing the gripper carries)."""
    frames = np.asarray(model.joint_frames(positions_rad))  # (N, dof+1, 4, 4)
    origins = frames[:, :, :3, 3]
    fractions = np.linspace(0.0, 1.0, LINK_POINTS_PER_SEGMENT, endpoint=False)[1:]
    between = origins[:, :-1, None, :] + fractions[None, None, :, None] * (origins[:, 1:, None, :] - origins[:, :-1, None, :])
    gripper = frames[:, -1]
    approach = gripper[:, :3, 0]  # the gripper's x axis points along the fingers
    tip = origins[:, -1] + approach * finger_length_m * 0.5
    points = [origins, between.reshape(len(origins), -1, 3), tip[:, None, :]]
    if held_edge_m is not None:
        points.append((origins[:, -1] + approach * held_edge_m)[:, None, :])
    return np.concatenate(points, axis=1)


# How far the links keep from an obstacle box (which is already wider than a block at any yaw): 8 mm beyond the
# link's surface. The tool's parts (fingers, palm, cup) and a held block are exact boxes that must come close to
# blocks to grasp them: they keep TOOL_CLEARANCE_M (as fingers_hit's margin).
CLEARANCE_M = 0.008
TOOL_CLEARANCE_M = 0.003


def first_collision(
    model,
    trajectory: JointTrajectory,
    boxes: list[ObstacleBox],
    *,
    margin_m: float = CLEARANCE_M,
    held_edge_m: float | None = None,
    gripper_checked_m: float = 0.0,
) -> str | None:
    """None when the arm's body (armlab.devices.arm_body: the links' capsules, the gripper's or cup's parts, a held
    block of held_edge_m) keeps margin_m (the tool and the held block: the smaller of it and TOOL_CLEARANCE_M) from
    every box at every sample, else a sentence naming the first box hit and when. The fingers stand open, or closed
    on the held block. gripper_checked_m > 0: the tool's own parts are left out (fingers_hit checks the gripper's
    box exactly there); the held block never is. The base's housings do not move (a box they touch at the start
    they touch throughout): the start rule below would leave them out anyway."""
    if not boxes:
        return None
    positions = trajectory.positions_rad[:: max(1, len(trajectory.positions_rad) // 40)]
    body = body_of(model)
    tool = len(model.joint_names) + 1
    gripper = getattr(model.config, "gripper", None)
    opening = None if held_edge_m is None or gripper is None else 0.5 * held_edge_m + gripper.pad_thickness_m
    placed = body.place(model, positions, finger_offset_m=opening, held_edge_m=held_edge_m)
    moving = [k for k, part in enumerate(placed.parts)
              if 0 < part.frame < tool and part.shape == "capsule" or part.frame == tool
              and (gripper_checked_m <= 0.0 or part.name == "held block")]
    capsules = [k for k in moving if placed.parts[k].shape == "capsule"]
    solids = [k for k in moving if placed.parts[k].shape != "capsule"]
    ends, radii = placed.segments(capsules)  # (N, C, 2, 3), (C,)
    poses, halves = placed.boxes(solids)
    tool_margin = min(margin_m, TOOL_CLEARANCE_M)
    for box in boxes:
        centre, half = _obstacle(box)
        hit = np.concatenate([_segments_near_box(ends, radii + margin_m, centre, half),
                              _boxes_near_box(poses, halves, centre, half + tool_margin)], axis=1)
        if hit[0].any():
            continue  # the arm starts this close (e.g. parked beside a block): moving away is the way out
        if hit.any():
            sample = int(np.argwhere(hit)[0][0])
            return f"the arm passes within {margin_m * 1000:.0f} mm of {box.name} (top {box.top_z_m * 1000:.0f} mm) at sample {sample}"
    return None


FLOOR_DEPTH_M = 1.0  # an obstacle box reaches this far below the board: whatever is under its top is inside it


def _obstacle(box: ObstacleBox) -> tuple[np.ndarray, np.ndarray]:
    """(centre, half extents) of an obstacle box as an axis-aligned box from below the board up to its top."""
    bottom = -FLOOR_DEPTH_M
    return (np.array([box.center_xy_m[0], box.center_xy_m[1], 0.5 * (box.top_z_m + bottom)]),
            np.array([box.half_xy_m[0], box.half_xy_m[1], 0.5 * (box.top_z_m - bottom)]))


def _segments_near_box(ends: np.ndarray, reach_m: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(N, C) bool: which segments (N, C, 2, 3) meet the box grown by their reach_m (C,) on every side (a slab test;
    a square-grown box: at its edges and corners up to sqrt(3) times the reach, on the safe side)."""
    p0, d = ends[:, :, 0] - centre, ends[:, :, 1] - ends[:, :, 0]
    grown = half[None, None, :] + reach_m[None, :, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t0, t1 = (-grown - p0) / d, (grown - p0) / d
    parallel = np.abs(d) < 1e-12
    inside_slab = np.abs(p0) <= grown
    lo = np.where(parallel, np.where(inside_slab, -np.inf, np.inf), np.minimum(t0, t1)).max(axis=-1)
    hi = np.where(parallel, np.where(inside_slab, np.inf, -np.inf), np.maximum(t0, t1)).min(axis=-1)
    return (np.maximum(lo, 0.0) <= np.minimum(hi, 1.0))


def _boxes_near_box(poses: np.ndarray, halves: np.ndarray, centre: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(N, B) bool: which oriented boxes (poses (N, B, 4, 4), half extents (B, 3)) overlap the axis-aligned box
    (centre, half): the separating-axis test over the 15 axes of two boxes."""
    R = poses[..., :3, :3]  # columns: the part's axes in the world
    A = np.abs(R) + 1e-9
    T = centre - poses[..., :3, 3]  # (N, B, 3)
    h = halves[None]  # (1, B, 3)
    separated = np.any(np.abs(T) > half + np.einsum("nbij,nbj->nbi", A, np.broadcast_to(h, T.shape)), axis=-1)
    along = np.einsum("nbij,nbi->nbj", R, T)
    separated |= np.any(np.abs(along) > np.einsum("nbij,i->nbj", A, half) + h, axis=-1)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            t = np.abs(T[..., i2] * R[..., i1, j] - T[..., i1] * R[..., i2, j])
            ra = half[i1] * A[..., i2, j] + half[i2] * A[..., i1, j]
            rb = h[..., j1] * A[..., i, j2] + h[..., j2] * A[..., i, j1]
            separated |= t > ra + rb
    return ~separated


def lowest_corners_m(model, positions_rad: np.ndarray, corners_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((N,) world z of the lowest of `corners_m` (K, 3) in the gripper frame, (N,) the gripper point's z) over joint
    vectors (N, dof): how low the fingers (a box around them) come at each sample."""
    T = np.asarray(model.fk(np.asarray(positions_rad, float)), float).reshape(-1, 4, 4)
    lowest = np.einsum("nj,kj->nk", T[:, 2, :3], np.asarray(corners_m, float)) + T[:, 2, 3][:, None]
    return lowest.min(axis=1), T[:, 2, 3]


def self_collision(
    model,
    positions_rad: np.ndarray,
    *,
    base_radius_m: float,
    reach_m: float = 0.03,
    finger_length_m: float = 0.03,
    held_edge_m: float | None = None,
) -> tuple[int, str, str] | None:
    """The first sample at which the gripper end of the arm (the gripper point, the finger tips, a held block's
    bottom: arm_points_m's last points, each reaching reach_m around it) meets the arm's own base (a cylinder
    of base_radius_m around the first joint's axis, up to the second joint's origin) or its first long link
    (the segment from the second joint's origin to the third's), as (sample, the part, what); None when it never
    does."""
    positions = np.atleast_2d(np.asarray(positions_rad, float))
    points = arm_points_m(model, positions, finger_length_m, held_edge_m)  # (N, P, 3)
    dof = int(model.dof)
    origins = points[:, : dof + 1]
    distal = [points[:, dof], points[:, -1 if held_edge_m is None else -2]]
    distal_names = ["gripper point", "finger tips"]
    if held_edge_m is not None:
        distal.append(points[:, -1])
        distal_names.append("held block")
    axis_xy, base_top = origins[:, 0, :2], origins[:, 1, 2]
    a, b = origins[:, 1], origins[:, 2]
    d = np.stack(distal, axis=1)  # (N, K, 3)
    radial = np.linalg.norm(d[:, :, :2] - axis_xy[:, None, :], axis=2)
    in_base = (radial < base_radius_m + reach_m) & (d[:, :, 2] < base_top[:, None] + reach_m)
    ab = (b - a)[:, None, :]
    along = np.clip(np.sum((d - a[:, None, :]) * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=2), 1e-12), 0.0, 1.0)
    gap = np.linalg.norm(d - (a[:, None, :] + along[..., None] * ab), axis=2)
    near_link = gap < 2.0 * reach_m
    hits = np.argwhere(in_base | near_link)
    if hits.size:
        sample, k = (int(v) for v in hits[0])
        name, point = distal_names[k], d[sample, k]
        if in_base[sample, k]:
            return sample, name, (f"the {name} would reach the arm's own base ({radial[sample, k] * 1000:.0f} mm from its "
                                  f"axis at z = {point[2] * 1000:.0f} mm; the base is {base_radius_m * 1000:.0f} mm wide up "
                                  f"to {base_top[sample] * 1000:.0f} mm)")
        return sample, name, f"the {name} would come within {gap[sample, k] * 1000:.0f} mm of the arm's upper arm"
    return None


OBJECT_BOX_RADIUS_M = 0.032  # half-width of the box around a detected object (a 38 mm cube at any yaw + margin)
FINGER_GRID = (4, 5, 2)  # points of the finger box sampled along its approach, closing and normal axes


def fingers_hit(model, trajectory: JointTrajectory, fingers, boxes: list[ObstacleBox], margin_m: float = 0.003) -> str | None:
    """None when the box the gripper occupies (`fingers`: armlab.motion.gripper_step.FingerBox, open fingers or
    a cup, in the gripper frame) stays margin_m outside every box at every sample, else a sentence naming the box
    and how low the gripper point was. The link check (first_collision) sees the finger tips only, not how wide
    open fingers reach sideways: a straight descent beside a stack needs this one."""
    if not boxes:
        return None
    nx, ny, nz = FINGER_GRID
    grid = np.array([[x, y, z] for x in np.linspace(-fingers.back_m, fingers.reach_m, nx)
                     for y in np.linspace(-fingers.half_width_m, fingers.half_width_m, ny)
                     for z in np.linspace(-fingers.half_height_m, fingers.half_height_m, nz)])
    positions = trajectory.positions_rad[:: max(1, len(trajectory.positions_rad) // 40)]
    T = np.asarray(model.fk(np.asarray(positions, float)), float).reshape(-1, 4, 4)
    points = np.einsum("nij,kj->nki", T[:, :3, :3], grid) + T[:, None, :3, 3]  # (N, K, 3)
    for box in boxes:
        inside = ((np.abs(points[..., 0] - box.center_xy_m[0]) < box.half_xy_m[0] + margin_m)
                  & (np.abs(points[..., 1] - box.center_xy_m[1]) < box.half_xy_m[1] + margin_m)
                  & (points[..., 2] < box.top_z_m + margin_m))
        if inside[0].any():
            continue  # the gripper starts this close (e.g. right after setting a block down there): moving away is the way out
        if inside.any():
            sample = int(np.argwhere(inside)[0][0])
            return (f"the open fingers would touch {box.name} (top {box.top_z_m * 1000:.0f} mm) with the gripper point at "
                    f"z = {T[sample, 2, 3] * 1000:.0f} mm")
    return None
