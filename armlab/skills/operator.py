"""The operator's long actions as jobs: calibrate, click-grab, click-drop (repeat a program: repeat.py).

Each validates and plans first (bad input, unreachable target, no calibration: an exception before
anything moves), then starts a job on the gate whose steps run through its guarded
run_trajectory/run_gripper.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from armlab.skills.clear_path import known_obstacles, plan_clear_pick, plan_clear_place
from armlab.skills.manipulate import run_steps
from armlab.skills.operator_advice import advised
from armlab.skills.perceive import block_near, target_point
from armlab.station.arm_info import station_end_effector
from armlab.station.calibration_trust import calibration_summary
from armlab.station.core import Station
from armlab.station.held import HeldBlock
from armlab.station.jobs import Job, JobContext
from armlab.station.telemetry import block_to_dict
from armlab.vision import calibrate_extrinsics, detect_tags
from armlab.vision.calibration import project_grid
from armlab.vision.click_calibration import calibrate_from_points

BOARD_NOISE_M = 0.006  # depth readings this close to the board are the board


class GripperEmpty(RuntimeError):
    """A grab closed on nothing, or a drop was asked with nothing in the gripper: the job fails saying so."""


def block_edge_m(station: Station, size: str | None) -> float:
    """The edge of a block of `size` (perception config, filled from the workcell); the default when unknown."""
    if size not in ("large", "small") or station.perception_config is None:
        return station.config.default_block_height_m
    return float(getattr(station.perception_config.blocks, f"{size}_size_m"))


def calibrate(station: Station, source: str | None = None) -> Job:
    """Start the calibration job: tags → extrinsics (+ depth cross-check) → saved and installed."""
    asked_s = time.time()

    def run(ctx: JobContext) -> dict:
        ctx.progress(0.1, "finding the board tags")
        frame = station.frame_after(asked_s)  # not a frame from before the request (the scene may just have changed)
        intrinsics = station.intrinsics.current()  # measured for this camera, else its own
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


def calibrate_points(station: Station, pixels_px: Sequence, world_m: Sequence, source: str | None = None) -> Job:
    """Start a calibration job from >= 4 clicked pixels and their known world points (no tags needed):
    homography + PnP with the camera's intrinsics, cross-checked with the newest depth; saved and
    installed. A bad set of points fails the job saying why and keeps the old calibration."""
    asked_s = time.time()

    def run(ctx: JobContext) -> dict:
        frame = station.frame_after(asked_s)
        intrinsics = station.intrinsics.current()  # measured for this camera, else its own
        ctx.progress(0.3, f"fitting the camera pose to {len(pixels_px)} clicked points")
        calibration, report = calibrate_from_points(pixels_px, world_m, intrinsics, station.perception_config, frame.depth_mm)
        info = {**calibration_summary(calibration, [], project_grid(calibration, station.perception_config)),
                "method": "points", "points": report}
        ctx.check()
        station.store.save_calibration({"calibration": calibration.to_dict(), "info": info})
        station.set_calibration(calibration, info)
        ctx.job.update(message=f"calibrated from {len(pixels_px)} points: reprojection error {calibration.reprojection_error_px:.2f} px")
        return {"reprojection_error_px": report["reprojection_error_px"], "homography_error_px": report.get("homography_error_px"),
                "point_errors_px": report["point_errors_px"], "camera_position_m": [float(x) for x in calibration.camera_position_m],
                "depth_check_error_m": report["depth_check_error_m"]}

    return station.start_job("calibrate", "calibrate", run, detail="from clicked points", source=source)


def base_xy_m(station: Station):
    """The arm base's world x, y (for saying how far a spot is from it)."""
    return np.asarray(station.model.T_world_base, dtype=float)[:2, 3]


def with_advice(what: str, point_m, call, base_xy_m=None):
    """call(); a refusal the operator can act on is re-raised saying what to do (operator_advice)."""
    try:
        return call()
    except Exception as error:
        better = advised(what, point_m, error, base_xy_m)
        if better is None:
            raise
        raise better from error


def grab(station: Station, position_m=None, pixel=None, source: str | None = None, check_only: bool = False,
         plan_only: bool = False) -> Job | str | dict:
    """Pick the detected block under the click (its centre, top and yaw), else at the clicked world point.
    check_only: plan it as the grab would and return what it would do (the page's reach state before a click);
    the same refusals (out of reach, hidden, unsafe, untrusted), nothing moves, any state. plan_only: keep the
    plan (Station.plan_steps: its wire form is returned, nothing moves); Execute runs exactly its steps."""
    if check_only:
        station.require_arm("grab")
    else:
        station.allowed_or_raise("grab")
    station.require_trusted_calibration("grab")
    point, on = target_point(station, position_m, pixel)
    near = block_near(station, point) if station.calibration is not None else None
    block_id, block = near if near is not None else (None, None)
    if block is not None:
        top = np.asarray(block.position_m, dtype=float)
        yaw, edge = block.yaw_rad, block_edge_m(station, block.size)
        detail = f"{block.size} {block.color} block at ({top[0] * 1000:.0f}, {top[1] * 1000:.0f}) mm"
    else:
        top, yaw, edge = point, None, station.config.default_block_height_m
        detail = f"point ({top[0] * 1000:.0f}, {top[1] * 1000:.0f}, {top[2] * 1000:.0f}) mm ({on})"
    boxes = known_obstacles(station, top, *([top] if block is not None else []))

    def plan() -> list:  # clear of every other block and stack the station sees (issue 21)
        return plan_clear_pick(station, top, yaw, edge, boxes)

    steps = with_advice("grab", top, plan, base_xy_m(station))
    if check_only:
        return f"grab {detail}"

    def run(ctx: JobContext, replan=plan) -> dict:
        with_advice("grab", top, lambda: run_steps(station, ctx, steps, replan=replan))
        holding = bool(station.gripper.read_state().holding)
        known = {"color": block.color, "size": block.size} if block is not None else {}
        station.set_held_block(HeldBlock(edge_m=edge, yaw_rad=yaw, **known) if holding else None)
        if not holding:
            raise GripperEmpty(f"nothing in the gripper: {station_end_effector(station).missed_grasp} at {detail}")
        ctx.job.update(message="holding the block")
        wire_block = None if block is None else block_to_dict(block_id, block)  # the job's result: the detection's wire dict
        return {"target_m": [float(x) for x in top], "yaw_rad": yaw, "block": wire_block, "holding": holding}

    return _started_or_planned(station, "grab", steps, run, detail, source, plan_only)


def _started_or_planned(station: Station, command: str, steps: list, run, detail: str, source: str | None,
                        plan_only: bool) -> Job | dict:
    """The skill's job started (run(ctx) may plan again if the arm moved), or with plan_only its plan kept: Execute
    starts the job running exactly `steps` (no replanning: a plan gone stale is refused instead)."""
    if not plan_only:
        return station.start_job(command, command, run, detail=detail, source=source)
    exactly = lambda ctx: run(ctx, replan=None)  # noqa: E731
    return station.plan_steps(command, steps, lambda: station.start_job(command, command, exactly, detail=detail, source=source),
                              source=source)


def drop(station: Station, position_m=None, pixel=None, source: str | None = None, check_only: bool = False,
         plan_only: bool = False) -> Job | str | dict:
    """Place the held block at the clicked spot, on whatever is there (board or the top of a stack).
    check_only, plan_only: as grab's."""
    if check_only:
        station.require_arm("drop")
    else:
        station.allowed_or_raise("drop")
    station.require_trusted_calibration("drop")
    point, on = target_point(station, position_m, pixel)
    surface = point.copy()
    yaw = None
    near = block_near(station, point) if station.calibration is not None else None
    below = near[1] if near is not None else None
    if below is not None:  # stack on it: centre on its top face, align with its yaw
        surface = np.asarray(below.position_m, dtype=float)
        yaw = below.yaw_rad
        on = f"{below.color} block"
    surface[2] = surface[2] if surface[2] > BOARD_NOISE_M else 0.0  # depth noise on the board reads as board
    held = station.held_block
    edge = float(held.edge_m if held is not None else station.config.default_block_height_m)
    boxes = known_obstacles(station, surface, *([surface] if below is not None else []))

    def plan() -> list:  # clear of every other block and stack the station sees (issue 21)
        return plan_clear_place(station, surface, yaw, edge, boxes)

    steps = with_advice("drop", surface, plan, base_xy_m(station))
    detail = f"onto {on} at ({surface[0] * 1000:.0f}, {surface[1] * 1000:.0f}, {surface[2] * 1000:.0f}) mm"
    if check_only:
        return f"drop {detail}"

    def run(ctx: JobContext, replan=plan) -> dict:
        if not station.gripper.read_state().holding:  # checked in the job: the page shows why it failed
            station.set_held_block(None)
            raise GripperEmpty("the gripper is empty: nothing to drop (grab a block first)")
        with_advice("drop", surface, lambda: run_steps(station, ctx, steps, replan=replan))
        station.set_held_block(None)
        return {"target_m": [float(x) for x in surface], "on": on}

    return _started_or_planned(station, "drop", steps, run, detail, source, plan_only)
