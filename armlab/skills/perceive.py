"""Perception skills: pixel → world, the detected block under a point, and a fresh look at the board.

They read the gate's frames and perception (armlab.station) and never move anything.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.errors import InvalidInput, SpotHidden
from armlab.station.checks import checked_position
from armlab.station.core import NotCalibrated, Station
from armlab.station.jobs import JobContext
from armlab.vision.block import Block
from armlab.vision.config import SelfFilterConfig
from armlab.vision.geometry import backproject, project_points, transform_points
from armlab.vision.pixel_world import pixel_to_world_off_robot
from armlab.vision.self_filter import robot_volume


def finite_pixel(u, v) -> tuple[float, float]:
    """(u, v) as finite floats, else ValueError."""
    try:
        u, v = float(u), float(v)
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"pixel must be two numbers, got ({u!r}, {v!r})") from error
    if not (math.isfinite(u) and math.isfinite(v)):
        raise InvalidInput("pixel (u, v) must be finite")
    return u, v


def pixel_to_world(station: Station, u: float, v: float) -> dict:
    """{position_m, on}: the world point under pixel (u, v), never on the robot. 'depth': the newest
    frame's depth outside the arm's volume (FK of the joints the frame was taken at + the calibration);
    'remembered': under the arm, the depth last seen there without it; else 'board' (z = 0)."""
    u, v = finite_pixel(u, v)
    calibration = station.calibration
    if calibration is None:
        raise NotCalibrated("pixel-to-world")
    frame, _ = station.frames.get()
    perception, _ = station.perception.get()
    depth = frame.depth_mm if frame is not None else None
    remembered = perception.surface_depth_mm if perception is not None else None
    robot = robot_volume_of(station, frame) if depth is not None else None
    if depth is not None and robot is None and getattr(station, "has_arm", True):
        depth = None  # the arm's pose is unknown: its depth cannot be told from the board's (no arm: all depth is the scene's)
    point, on = pixel_to_world_off_robot(calibration, u, v, depth, robot, remembered)
    if on == "remembered":
        seen_s = _seen_time_s(perception, u, v)
        if seen_s is None or station.changed_at_since(point, seen_s):
            raise SpotHidden(
                f"the spot at ({point[0] * 1000:.0f}, {point[1] * 1000:.0f}) mm is hidden under the arm and the gripper went down "
                "there since it was last seen (a drop, a grab or a move through it): move the arm out of the camera's view "
                "(Sleep) to look again, then click")
    return {"position_m": [float(x) for x in point], "on": on}


def _seen_time_s(perception, u: float, v: float, radius: int = 1) -> float | None:
    """When the remembered depth around pixel (u, v) was seen: the oldest of the window's seen pixels (None: unknown)."""
    times = getattr(perception, "surface_time_s", None)
    if times is None:
        return None
    ui, vi = int(round(u)), int(round(v))
    window = times[max(0, vi - radius): vi + radius + 1, max(0, ui - radius): ui + radius + 1]
    seen = window[window > 0]
    return float(seen.min()) if seen.size else None


def robot_volume_of(station: Station, frame):
    """The robot's inflated volume (armlab.vision.self_filter) at the joints `frame` was taken at, with a
    held block unless the gripper was open; None when the frame has no joints or the station no arm model."""
    joints = getattr(frame, "arm_joints_rad", None)
    if joints is None or station.model is None:
        return None
    config = station.perception_config.self_filter if station.perception_config is not None else SelfFilterConfig()
    held_edge_m = 0.0 if frame.gripper_closed is False else None
    return robot_volume(station.model, np.asarray(joints, dtype=float), config, held_edge_m)


def arm_hides_block(station: Station, joints_rad, xy_m, edge_m: float) -> bool:
    """True when the arm at joints_rad (gripper open) would hide part of a block of edge_m standing at xy_m
    on the board from the calibrated camera (a block put there would read occluded while the arm waits
    there); False without a calibration or an arm model."""
    calibration = station.calibration
    if calibration is None or station.model is None:
        return False
    perception_config = getattr(station, "perception_config", None)
    config = perception_config.self_filter if perception_config is not None else SelfFilterConfig()
    volume = robot_volume(station.model, np.asarray(joints_rad, dtype=float), config, 0.0)
    half = 0.5 * edge_m
    top = [(xy_m[0] + dx, xy_m[1] + dy, edge_m) for dx in (-half, 0.0, half) for dy in (-half, 0.0, half)]
    return volume.hides(np.asarray(calibration.T_world_camera)[:3, 3], np.array(top))


def target_point(station: Station, position_m, pixel) -> tuple[np.ndarray, str]:
    """The clicked world point from position_m or pixel=(u, v) (exactly one of them)."""
    if (position_m is None) == (pixel is None):
        raise InvalidInput("give either position_m or a pixel (u, v), not both or neither")
    if pixel is not None:
        result = pixel_to_world(station, *pixel)
        return np.asarray(result["position_m"]), result["on"]
    return checked_position(position_m), "given"


def block_near(station: Station, point_m: np.ndarray) -> tuple[int, Block] | None:
    """The detected block whose top centre is nearest `point_m` in x-y, within click_snap_radius_m, with its index
    among the detections (its wire id)."""
    best, best_distance = None, station.config.click_snap_radius_m
    for index, block in enumerate(station.detections().blocks):
        distance = math.dist(block.position_m[:2], point_m[:2])
        if distance <= best_distance:
            best, best_distance = (index, block), distance
    return best


def look(station: Station, ctx: JobContext | None = None) -> list[Block]:
    """The blocks seen in a frame taken after the arm last moved, in detection order, each with the frame's
    capture time (seen_time_s) and the arm's joints then (seen_arm_joints_rad, when perception knew them).

    NotCalibrated without a calibration: blocks need one."""
    if station.calibration is None:
        raise NotCalibrated("looking at the board")
    return list(station.fresh_perception(ctx).seen_blocks())


def is_stale(station: Station, block: Block) -> bool:
    """True if the arm moved over the block's spot after the block was seen (do not act on it)."""
    return station.moved_over_since(block.position_m, float(block.seen_time_s or 0.0))


def surface_height_m(station: Station, xy_m, radius_m: float = 0.008, max_height_m: float = 0.6,
                     unseen: float | None = 0.0) -> float | None:
    """The height of whatever stands at world (x, y), measured in the newest depth image: the highest
    z whose point projects to a pixel whose depth lands back within radius_m of (x, y) at that height
    (a ray cast down the column onto the depth surface). 0.0 for the bare board; `unseen` when no
    height at (x, y), not even the board's, is seen (e.g. a column whose top is outside the image and
    whose body hides its base); NotCalibrated without a calibration; ValueError without depth."""
    calibration = station.calibration
    if calibration is None:
        raise NotCalibrated("measuring a height")
    frame, _ = station.frames.get()
    if frame is None or frame.depth_mm is None:
        raise InvalidInput("measuring a height needs a depth image")
    heights = np.arange(max_height_m, -0.0001, -0.004)
    points = np.column_stack([np.full_like(heights, float(xy_m[0])), np.full_like(heights, float(xy_m[1])), heights])
    pixels = project_points(calibration.T_world_camera, calibration.K, calibration.dist, points)
    rows, cols = np.round(pixels[:, 1]).astype(int), np.round(pixels[:, 0]).astype(int)
    depth = frame.depth_mm
    inside = (rows >= 0) & (rows < depth.shape[0]) & (cols >= 0) & (cols < depth.shape[1])
    depth_m = np.zeros(len(heights))
    depth_m[inside] = depth[rows[inside], cols[inside]] / 1000.0
    valid = inside & (depth_m > 0)
    if not valid.any():
        return unseen
    world = transform_points(calibration.T_world_depth, backproject(pixels[valid], depth_m[valid], calibration.K, calibration.dist))
    hits = (np.hypot(world[:, 0] - float(xy_m[0]), world[:, 1] - float(xy_m[1])) <= radius_m) & (np.abs(world[:, 2] - heights[valid]) <= 0.006)
    return float(max(0.0, world[hits, 2].max())) if hits.any() else unseen
