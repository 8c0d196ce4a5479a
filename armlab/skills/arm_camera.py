"""The camera calibrated from the arm, without board tags (issue 19 item 3, the Sawyer project's method):
the arm visits poses over the board (each move checked by the gate like any other), the camera finds the
gripper's tag (armlab.vision.gripper_marker) in each, forward kinematics gives the same point in the base
frame, Kabsch gives T_base_camera (armlab.vision.arm_camera). A job of its own; it cross-checks the tag
calibration in use (their disagreement in the result and the event log) and replaces it only when asked
(use=True): the tag calibration stays the station's default.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armlab.kinematics import Unreachable
from armlab.motion.safety import UnsafeTrajectory
from armlab.station.calibration_trust import calibration_summary
from armlab.station.core import Station
from armlab.station.jobs import Job, JobContext
from armlab.vision import Calibration, detect_tags
from armlab.vision.arm_camera import ArmCameraError, ArmCameraFit, fit_camera_from_arm, pose_difference
from armlab.vision.calibration import project_grid
from armlab.vision.geometry import invert_transform, project_points, transform_points
from armlab.vision.gripper_marker import MarkerNotFound, find_marker
from armlab.workcell import load_workcell

JOB_NAME, JOB_DETAIL = "calibrate-arm-camera", "from the arm (gripper tag + Kabsch)"
MIN_USABLE_POSES = 10  # poses whose gripper tag was seen: fewer and the fit is refused
MAX_RESIDUAL_M = 0.010  # mean residual above this: refused (the camera saw something else, or FK is off)
SETTLE_SPEED_RAD_S = 0.02  # the arm is still (for a frame) below this joint speed
AGREE_M, AGREE_DEG = 0.005, 0.5  # tag and arm calibrations further apart than this: a warning in the log


def sight_marker_at_rest(station: Station, ctx: JobContext, marker_id: int, K: np.ndarray, dist: np.ndarray):
    """The gripper's tag (armlab.vision.gripper_marker's sighting) in a frame taken once the arm has settled (the real
    arm's unloaded joints corrected, Station.settle_arm; its joints slower than SETTLE_SPEED_RAD_S, at most 2 s);
    MarkerNotFound when the camera does not find it."""
    station.settle_arm(ctx)
    station.wait_in_job(ctx, lambda: float(np.abs(station.arm.read_joint_state().velocity_rad_s).max()) < SETTLE_SPEED_RAD_S, 2.0)
    frame = station.frame_after(time.time())
    return find_marker(detect_tags(frame.color_bgr, station.perception_config), marker_id, frame.depth_mm, K, dist)


@dataclass(frozen=True)
class CalibrationPose:
    """Where the gripper point goes (world, metres), its pitch below the horizontal and its wrist_rotate
    (rad): level with wrist_rotate 0 puts the gripper's tag face up, toward the overhead camera."""

    position_m: tuple[float, float, float]
    pitch_rad: float = 0.0
    wrist_rotate_rad: float = 0.0


def default_poses() -> list[CalibrationPose]:
    """15 poses over the RX200 board: x -0.2..0.2 m, y 0.16..0.38 m, z 0.10..0.24 m (each height in every
    row and column), level or pitched 0.25 rad down, in a snake order so each move is short."""
    poses = []
    for j, y in enumerate((0.16, 0.27, 0.38)):
        xs = (-0.2, -0.1, 0.0, 0.1, 0.2)
        for i, x in enumerate(xs if j % 2 == 0 else xs[::-1]):
            z = (0.10, 0.17, 0.24)[(i + j) % 3]
            poses.append(CalibrationPose((x, y, z), 0.25 if (i + 2 * j) % 4 == 3 else 0.0))
    return poses


def calibrate_arm_camera(station: Station, poses: Sequence[CalibrationPose] | None = None, use: bool = False,
                         min_usable: int = MIN_USABLE_POSES, source: str | None = None) -> Job:
    """Start the job: visit the poses, find the gripper's tag in each, fit T_base_camera, compare it with
    the calibration in use; with use=True save and install it as the station's calibration. The job fails
    saying why (no marker in the workcell, a block held, fewer than min_usable poses seen, a bad fit),
    and then nothing changes: the calibration in use stays."""
    chosen = list(default_poses() if poses is None else poses)

    def run(ctx: JobContext) -> dict:
        marker = load_workcell(station.config.workcell).gripper.marker
        if marker is None:
            raise ArmCameraError(f"workcell '{station.config.workcell}' has no gripper marker (gripper.marker): "
                                 "the camera cannot find the gripper")
        if station.gripper.read_state().holding:
            raise ArmCameraError("the gripper holds something: put it down first (it may hide the gripper's tag)")
        intrinsics = station.intrinsics.current()
        K, dist = intrinsics.K, np.asarray(intrinsics.dist, dtype=float)
        T_base_world = invert_transform(np.asarray(station.model.T_world_base, float))
        q_start = station.joints_rad()
        seen_camera, seen_base, used, skipped, pixels = [], [], [], [], []
        for index, pose in enumerate(chosen):
            ctx.progress(index / (len(chosen) + 1), f"pose {index + 1} of {len(chosen)}")
            try:
                station.run_trajectory(ctx, station.plan_move(pose_joints(station, pose)))
            except (Unreachable, UnsafeTrajectory) as error:  # planned and checked before moving: nothing moved
                skipped.append({"pose": index, "reason": f"not visited: {error}"})
                continue
            try:
                sighting = sight_marker_at_rest(station, ctx, marker.id, K, dist)
            except MarkerNotFound as error:
                skipped.append({"pose": index, "reason": str(error)})
                continue
            q = station.joints_rad()
            seen_camera.append(sighting.point_camera_m)
            seen_base.append(transform_points(T_base_world @ station.model.fk(q), np.asarray(marker.position_m))[0])
            pixels.append(sighting.pixel)
            used.append(index)
        ctx.progress(len(chosen) / (len(chosen) + 1), "back to the start")
        station.run_trajectory(ctx, station.plan_move(q_start))
        fit = fit_camera_from_arm(np.array(seen_camera).reshape(-1, 3), np.array(seen_base).reshape(-1, 3),
                                  min_points=min_usable, max_residual_m=MAX_RESIDUAL_M)
        T_world_camera = np.asarray(station.model.T_world_base, float) @ fit.T_base_camera
        result = fit_summary(fit, T_world_camera, used, skipped, len(chosen))
        result["tag_calibration"] = cross_check(station, T_world_camera)
        ctx.check()
        if use:
            install(station, fit, T_world_camera, intrinsics, np.array(seen_base), np.array(pixels), result)
        ctx.job.update(message=log_result(station, result, use))
        return result

    return station.start_job("calibrate", JOB_NAME, run, detail=JOB_DETAIL, source=source)


def pose_joints(station: Station, pose: CalibrationPose) -> np.ndarray:
    """IK for a calibration pose from the current joints, wrist_rotate set; Unreachable if it is not."""
    q = station.model.ik(np.asarray(pose.position_m, float), pitch=pose.pitch_rad, q_seed=station.joints_rad())
    q[-1] = pose.wrist_rotate_rad
    if not station.model.within_limits(q):
        raise Unreachable(f"wrist_rotate {pose.wrist_rotate_rad:.2f} rad is beyond its limits")
    return q


def fit_summary(fit: ArmCameraFit, T_world_camera: np.ndarray, used: list[int], skipped: list[dict], planned: int) -> dict:
    """The job's result: poses used and skipped (why), residuals (mm, per pose used), the poses found."""
    residual_mm = fit.residuals_m * 1000.0
    return {
        "poses_planned": planned,
        "poses_used": used,
        "skipped": skipped,
        "residuals_mm": [round(float(r), 3) for r in residual_mm],
        "residual_mean_mm": float(residual_mm.mean()),
        "residual_max_mm": float(residual_mm.max()),
        "spread_m": [float(s) for s in fit.spread_m],
        "T_base_camera": fit.T_base_camera.tolist(),
        "T_world_camera": T_world_camera.tolist(),
        "camera_position_m": [float(x) for x in T_world_camera[:3, 3]],
        "message": (f"camera from the arm: {len(used)} of {planned} poses, residual {residual_mm.mean():.2f} mm mean, "
                    f"{residual_mm.max():.2f} mm max"),
    }


def cross_check(station: Station, T_world_camera: np.ndarray) -> dict | None:
    """Disagreement with the calibration in use (its depth camera's pose, as the arm's fit is), or None without one."""
    calibration = station.calibration
    if calibration is None:
        return None
    position_m, angle_deg = pose_difference(calibration.T_world_depth, T_world_camera)
    method = station.calibration_info.get("method") or "tags"
    return {"method": method, "position_mm": position_m * 1000.0, "rotation_deg": angle_deg,
            "agree": bool(position_m <= AGREE_M and angle_deg <= AGREE_DEG)}


def install(station: Station, fit: ArmCameraFit, T_world_camera: np.ndarray, intrinsics, points_base: np.ndarray,
            pixels: np.ndarray, result: dict) -> None:
    """Save and use the arm's camera pose as the station's calibration (method 'arm-camera'); its
    reprojection error is the gripper tag's centres projected from FK against where they were seen."""
    points_world = transform_points(np.asarray(station.model.T_world_base, float), points_base)
    projected = project_points(T_world_camera, intrinsics.K, np.asarray(intrinsics.dist, float), points_world)
    error_px = float(np.sqrt(np.mean(np.sum((projected - pixels) ** 2, axis=1))))
    calibration = Calibration(T_world_camera=T_world_camera, K=intrinsics.K, dist=np.asarray(intrinsics.dist, float),
                              width=intrinsics.width, height=intrinsics.height, reprojection_error_px=error_px)
    info = {**calibration_summary(calibration, [], project_grid(calibration, station.perception_config)), "method": "arm-camera"}
    station.store.save_calibration({"calibration": calibration.to_dict(), "info": info})
    station.set_calibration(calibration, info)
    result["installed"] = True
    result["reprojection_error_px"] = error_px


def log_result(station: Station, result: dict, used_now: bool) -> str:
    """One event (returned, for the job's message): the fit, and how far it is from the calibration in use
    (a warning when they disagree by more than AGREE_M or AGREE_DEG)."""
    check = result["tag_calibration"]
    if check is None:
        words = f"{result['message']}; no calibration in use to compare with"
        station.events.add("info", words)
        return words
    words = (f"{result['message']}; {check['position_mm']:.1f} mm and {check['rotation_deg']:.2f} deg from the "
             f"{check['method']} calibration" + (" (now replaced by it)" if used_now else ""))
    station.events.add("info" if check["agree"] else "warn", words)
    return words
