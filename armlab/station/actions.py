"""The station's long actions: calibrate, click-grab, click-drop, repeat a program, run a task.

Each public function validates and plans first (bad input, unreachable target, no calibration:
an exception before anything moves), then starts a job on the station whose steps are executed
through the station's guarded run_trajectory/run_gripper.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from armlab.station.checks import checked_position
from armlab.station.core import NotCalibrated, Station
from armlab.station.jobs import Job, JobContext
from armlab.station.telemetry import tag_to_dict

BLOCK_HEIGHTS_M = {"large": 0.038, "small": 0.025}
MAX_SURFACE_HEIGHT_M = 0.25  # a drop surface higher than this is taken for the arm hiding the spot
BOARD_NOISE_M = 0.006  # depth readings this close to the board are the board


# Frames and clicks -------------------------------------------------------------------------------


def newest_frame(station: Station, timeout_s: float = 2.0, max_age_s: float = 2.0):
    """The newest camera frame (waiting up to timeout_s for the first one, or for a fresh one when the
    newest is older than max_age_s); TimeoutError (a device error) if there is none."""
    frame, version = station.frames.get()
    if frame is None or time.time() - frame.timestamp_s > max_age_s:
        frame, _ = station.frames.wait_newer(version, timeout_s)
    if frame is None or time.time() - frame.timestamp_s > max_age_s + timeout_s:
        raise TimeoutError(f"no fresh camera frame within {timeout_s} s: is the camera running?")
    return frame


def _finite_pixel(u, v) -> tuple[float, float]:
    try:
        u, v = float(u), float(v)
    except (TypeError, ValueError) as error:
        raise ValueError(f"pixel must be two numbers, got ({u!r}, {v!r})") from error
    if not (math.isfinite(u) and math.isfinite(v)):
        raise ValueError("pixel (u, v) must be finite")
    return u, v


def pixel_to_world(station: Station, u: float, v: float) -> dict:
    """{position_m, on}: the world point under pixel (u, v); 'depth' from the depth image, else 'board' (z = 0)."""
    from armlab.vision import pixel_to_world as vision_pixel_to_world

    u, v = _finite_pixel(u, v)
    calibration = station.calibration
    if calibration is None:
        raise NotCalibrated("pixel-to-world")
    frame, _ = station.frames.get()
    if frame is not None and frame.depth_mm is not None:
        try:
            point = vision_pixel_to_world(calibration, u, v, depth_mm=frame.depth_mm)
            return {"position_m": [float(x) for x in point], "on": "depth"}
        except ValueError as error:
            if "outside" in str(error):
                raise
    point = vision_pixel_to_world(calibration, u, v)
    return {"position_m": [float(x) for x in point], "on": "board"}


def _target_point(station: Station, position_m, pixel) -> tuple[np.ndarray, str]:
    """The clicked world point from position_m or pixel=(u, v) (exactly one of them)."""
    if (position_m is None) == (pixel is None):
        raise ValueError("give either position_m or a pixel (u, v), not both or neither")
    if pixel is not None:
        result = pixel_to_world(station, *pixel)
        return np.asarray(result["position_m"]), result["on"]
    return checked_position(position_m), "given"


def block_near(station: Station, point_m: np.ndarray) -> dict | None:
    """The detected block whose top centre is nearest `point_m` in x-y, within click_snap_radius_m."""
    best, best_distance = None, station.config.click_snap_radius_m
    for block in station.detections()["data"]:
        distance = math.dist(block["position_m"][:2], point_m[:2])
        if distance <= best_distance:
            best, best_distance = block, distance
    return best


# Planning ------------------------------------------------------------------------------------------


def _motion_config(station: Station):
    if station.motion_config is None:
        from armlab.motion.config import load_motion_config

        station.motion_config = load_motion_config()
    return station.motion_config


def _q_now(station: Station) -> np.ndarray:
    return np.asarray(station.arm.read_joint_state().position_rad, dtype=float)


def plan_pick_steps(station: Station, top_center_m: np.ndarray, yaw_rad: float | None) -> list:
    """armlab.motion's pick plan from the current joints (open, above, straight down, grasp, straight up).

    Unreachable / UnsafeTrajectory / ValueError before anything moves.
    """
    from armlab.motion import plan_pick

    return plan_pick(station.model, _q_now(station), top_center_m, 0.0 if yaw_rad is None else yaw_rad, _motion_config(station))


def plan_place_steps(station: Station, surface_m: np.ndarray, yaw_rad: float | None, held_height_m: float) -> list:
    """armlab.motion's place plan: the held block's bottom centre onto surface_m, then release and retreat."""
    from armlab.motion import plan_place

    yaw = 0.0 if yaw_rad is None else yaw_rad
    return plan_place(station.model, _q_now(station), surface_m, yaw, _motion_config(station), held_height_m)


def run_steps(station: Station, ctx: JobContext, steps: Sequence, replan: Callable[[], list] | None = None) -> None:
    """Execute motion steps (TrajectoryStep / GripperStep) through the station's guards, with progress.

    If the arm is no longer where the plan starts (it moved since planning), `replan()` plans again.
    """
    from armlab.motion import TrajectoryStep

    first = next((step for step in steps if isinstance(step, TrajectoryStep)), None)
    if replan is not None and first is not None and np.abs(first.trajectory.positions_rad[0] - _q_now(station)).max() > 0.01:
        steps = replan()
    for index, step in enumerate(steps):
        ctx.progress(index / len(steps), step.name)
        if isinstance(step, TrajectoryStep):
            station.run_trajectory(ctx, step.trajectory)
        else:
            station.run_gripper(ctx, step.action)
    ctx.progress(1.0, "done")


# Jobs ----------------------------------------------------------------------------------------------


def calibrate(station: Station, source: str | None = None) -> Job:
    """Start the calibration job: tags → extrinsics (+ depth cross-check) → saved and installed."""
    from armlab.vision import calibrate_extrinsics, detect_tags
    from armlab.vision.calibration import project_grid

    def run(ctx: JobContext) -> dict:
        ctx.progress(0.1, "finding the board tags")
        frame = newest_frame(station)
        intrinsics = frame.intrinsics or station.camera.intrinsics
        tags = detect_tags(frame.color_bgr, station.perception_config)
        ctx.progress(0.4, f"{len(tags)} tags found; solving the camera pose")
        calibration = calibrate_extrinsics(frame.color_bgr, intrinsics, station.perception_config, frame.depth_mm, tags=tags)
        info = calibration_summary(calibration, tags, project_grid(calibration, station.perception_config))
        ctx.check()
        station.store.save_calibration({"calibration": calibration.to_dict(), "info": info})
        station.set_calibration(calibration, info)
        ctx.job.update(message=f"calibrated: reprojection error {calibration.reprojection_error_px:.2f} px")
        return {key: info[key] for key in ("reprojection_error_px", "camera_position_m", "depth_check_error_m")}

    return station.start_job("calibrate", "calibrate", run, source=source)


def calibration_summary(calibration: Any, tags: Sequence, grid_px: np.ndarray) -> dict:
    """The wire dict of GET /api/calibration (without 'calibrated')."""
    depth_error = calibration.depth_check_error_m
    return {
        "reprojection_error_px": float(calibration.reprojection_error_px),
        "camera_position_m": [float(x) for x in calibration.camera_position_m],
        "T_world_camera": np.asarray(calibration.T_world_camera, dtype=float).tolist(),
        "K": np.asarray(calibration.K, dtype=float).tolist(),
        "dist": np.asarray(calibration.dist, dtype=float).ravel().tolist(),
        "width": int(calibration.width),
        "height": int(calibration.height),
        "depth_check_error_m": None if depth_error is None else float(depth_error),
        "grid_points_px": np.asarray(grid_px, dtype=float).round(2).tolist(),
        "tags": [tag_to_dict(tag) for tag in tags],
        "time": time.time(),
    }


def grab(station: Station, position_m=None, pixel=None, source: str | None = None) -> Job:
    """Pick the detected block under the click (its centre, top and yaw), else at the clicked world point."""
    station.allowed_or_raise("grab")
    point, on = _target_point(station, position_m, pixel)
    block = block_near(station, point) if station.calibration is not None else None
    if block is not None:
        top = np.asarray(block["position_m"], dtype=float)
        yaw, height = block["yaw_rad"], BLOCK_HEIGHTS_M.get(block["size"], station.config.default_block_height_m)
        detail = f"{block['size']} {block['color']} block at ({top[0] * 1000:.0f}, {top[1] * 1000:.0f}) mm"
    else:
        top, yaw, height = point, None, station.config.default_block_height_m
        detail = f"point ({top[0] * 1000:.0f}, {top[1] * 1000:.0f}, {top[2] * 1000:.0f}) mm ({on})"
    steps = plan_pick_steps(station, top, yaw)

    def run(ctx: JobContext) -> dict:
        run_steps(station, ctx, steps, replan=lambda: plan_pick_steps(station, top, yaw))
        holding = bool(station.gripper.read_state().holding)
        station.held_block = {**(block or {}), "height_m": height, "yaw_rad": yaw} if holding else None
        ctx.job.update(message="holding the block" if holding else "nothing in the gripper")
        return {"target_m": [float(x) for x in top], "yaw_rad": yaw, "block": block, "holding": holding}

    return station.start_job("grab", "grab", run, detail=detail, source=source)


def drop(station: Station, position_m=None, pixel=None, source: str | None = None) -> Job:
    """Place the held block at the clicked spot, on whatever is there (board or the top of a stack)."""
    station.allowed_or_raise("drop")
    point, on = _target_point(station, position_m, pixel)
    surface = point.copy()
    yaw = None
    below = block_near(station, point) if station.calibration is not None else None
    if below is not None:  # stack on it: centre on its top face, align with its yaw
        surface = np.asarray(below["position_m"], dtype=float)
        yaw = below["yaw_rad"]
        on = f"{below['color']} block"
    elif on == "depth" and surface[2] > MAX_SURFACE_HEIGHT_M:  # the arm (or the held block) hides the spot
        from armlab.vision import pixel_to_world as vision_pixel_to_world

        surface, on = np.asarray(vision_pixel_to_world(station.calibration, *_finite_pixel(*pixel)), dtype=float), "board"
    surface[2] = surface[2] if surface[2] > BOARD_NOISE_M else 0.0  # depth noise on the board reads as board
    held = station.held_block or {}
    height = float(held.get("height_m", station.config.default_block_height_m))
    steps = plan_place_steps(station, surface, yaw, height)
    detail = f"onto {on} at ({surface[0] * 1000:.0f}, {surface[1] * 1000:.0f}, {surface[2] * 1000:.0f}) mm"

    def run(ctx: JobContext) -> dict:
        run_steps(station, ctx, steps, replan=lambda: plan_place_steps(station, surface, yaw, height))
        station.held_block = None
        return {"target_m": [float(x) for x in surface], "on": on}

    return station.start_job("drop", "drop", run, detail=detail, source=source)


def repeat(station: Station, program_id: int, cycles: int = 1, source: str | None = None) -> Job:
    """Play a saved program `cycles` times: joint moves between waypoints, gripper changes where taught."""
    station.allowed_or_raise("repeat")
    if not isinstance(cycles, int) or not 1 <= cycles <= 100:
        raise ValueError(f"cycles must be an integer from 1 to 100, got {cycles!r}")
    program = station.store.get_program(program_id)
    for waypoint in program.waypoints:
        station._checked_joints(waypoint.joints_rad)

    def run(ctx: JobContext) -> dict:
        total = cycles * len(program.waypoints)
        done = 0
        for cycle in range(cycles):
            for index, waypoint in enumerate(program.waypoints):
                ctx.progress(done / total, f"cycle {cycle + 1}/{cycles}, waypoint {index + 1}/{len(program.waypoints)}")
                station.move_in_job(ctx, waypoint.joints_rad)
                if station.gripper.read_state().command != waypoint.gripper:
                    station.run_gripper(ctx, waypoint.gripper)
                done += 1
        return {"program_id": program.id, "cycles": cycles}

    return station.start_job("repeat", "repeat", run, detail=f"program '{program.name}' × {cycles}", source=source)


def run_task(station: Station, name: str, function: Callable[[Station, JobContext], Any], source: str | None = None) -> Job:
    """Run an autonomous task (sort, stack, ...) as the auto_sort job; function(station, ctx) uses
    station.move_in_job / run_gripper / plan_pick_steps so e-stop and cancel apply to it too."""
    return station.start_job("auto", name, lambda ctx: function(station, ctx), detail=name, source=source)
