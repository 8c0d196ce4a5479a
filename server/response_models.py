"""Response bodies of the REST routes: errors, the station's status, jobs, detections, calibration."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from server.wire_base import Vector3, Wire


class ErrorBody(Wire):
    code: str
    message: str
    allowed: list[str] | None = None
    reason: str | None = Field(None, description="why a plan is stale (stale_plan): executed, expired, arm_moved, arm_commanded, ...")
    part: str | None = Field(None, description="the joint or part of the arm a refused motion names (unsafe); "
                             "GET /api/view3d/scene's arm.part_links names its links")
    at_q_rad: list[float] | None = Field(None, description="the joints (rad) at the refused motion's first offending sample (unsafe)")


class ErrorResponse(Wire):
    error: ErrorBody


class GripperStatus(Wire):
    width_m: float
    holding: bool
    command: str


class GripperPose(Wire):
    position_m: Vector3
    pitch_rad: float
    yaw_rad: float


class JobInfo(Wire):
    id: str
    name: str
    detail: str = ""
    state: Literal["running", "succeeded", "failed", "cancelled"]
    progress: float
    message: str
    started_s: float
    finished_s: float | None = None
    result: Any = None
    extra: dict[str, Any] | None = Field(None, description="job-specific live details; autonomous jobs: {task: TaskProgress}")


class JobResponse(Wire):
    job: JobInfo | None


class ArmCalibrationStatus(Wire):
    calibrated: bool
    residual_mm: float | None = Field(None, description="the arm calibration's mean residual (mm) at the gripper tag")
    at: float | None = Field(None, description="when it was made (time.time())")


class Status(Wire):
    state: Literal["idle", "calibrate", "teach", "repeat", "click_grab", "click_drop", "auto_sort", "estop", "fault"]
    detail: str
    joints_rad: list[float]
    commanded_joints_rad: list[float] | None = Field(None, description="the commanded reference now (the last "
                                                     "trajectory sent, at the station's clock; its end once it has run "
                                                     "out): the measured joints trail it; None before any motion was "
                                                     "sent or after a halt")
    joint_names: list[str]
    joint_limits_rad: list[list[float]] = Field(description="[lower, upper] per joint")
    gripper: GripperStatus
    gripper_pose: GripperPose | None = Field(description="the gripper's pose (FK of the joints); None on a station with no arm")
    moving: bool
    torque_enabled: bool = Field(True, description="motor torque on (the arm holds); off = limp, it falls unless held")
    calibrated: bool
    camera_warning: str | None = Field(None, description='"camera moved: recalibrate (...)" when the board tags no longer sit where the calibration puts them')
    calibration_state: Literal["checking", "trusted", "untrusted", "rejected"] | None = Field(
        None, description="trusted: in use; untrusted: in use, but the board tags do not confirm it (camera_warning says "
        "why): grabs, drops and jobs are refused; checking: restored at start, not used until the board tags confirm it; "
        "rejected: restored but the camera moved since (recalibrate); None: no calibration")
    arm_calibration: ArmCalibrationStatus | None = Field(None, description="the arm's calibration from the camera "
                                                         "(POST /api/calibrate/arm); None on a station with no arm")
    self_recalibrate: bool = Field(False, description="the station recalibrates itself from the board tags when idle once the "
                                   "camera moved (PUT /api/calibration/settings)")
    backend: Literal["sim", "real"]
    controller: str | None = Field(description="who holds the control lease (None: free); only it may command")
    controller_since_s: float | None = Field(None, description="when it took control (time.time())")
    devices_lost: dict[str, str] = Field(default_factory=dict, description="devices not answering, with the reason")
    speed_percent: float = Field(100.0, description="the speed override (PUT /api/speed), % of full speed, of every motion")
    job: JobInfo | None
    allowed_commands: list[str]
    time_s: float


class Detection(Wire):
    id: int
    color: str | None
    size: str | None
    position_m: Vector3 = Field(description="top face centre, world frame")
    yaw_rad: float
    height_m: float
    stack_level: int
    center_px: list[float]
    is_cube: bool
    occluded: bool
    aruco_id: int | None = None
    destination: Any = None
    color_lab: list[float] | None = Field(None, description="the top face's colour, board-normalised CIELAB (L, a, b): "
                                          "what an 'unknown' colour measured")


class DetectionsResponse(Wire):
    data: list[Detection]
    count: int
    time_s: float
    frame_sequence: int
    stale: bool = Field(False, description="True while the camera is lost or perception is old: data is then empty")
    stale_reason: str | None = None


class TagInfo(Wire):
    id: int
    center_px: list[float]
    corners_px: list[list[float]]
    hamming: int | None = Field(None, description="bits the decoder corrected (None: an OpenCV ArUco dictionary does not say)")
    decision_margin: float | None = Field(None, description="the AprilTag library's confidence (higher is surer; None for ArUco)")


class CalibrationInfo(Wire):
    calibrated: bool
    reprojection_error_px: float | None = None
    camera_position_m: Vector3 | None = None
    T_world_camera: list[list[float]] | None = None
    K: list[list[float]] | None = None
    dist: list[float] | None = None
    width: int | None = None
    height: int | None = None
    depth_check_error_m: float | None = None
    depth_offset_m: float | None = Field(None, description="the depth camera's board plane above (+) or behind (-) the tags' plane")
    depth_tilt_deg: float | None = Field(None, description="angle between the depth camera's board plane and the tags' plane")
    depth_model: str | None = Field(None, description="the two in words, e.g. 'depth 8.3 mm behind the tags' plane, tilted 1.52 deg'")
    grid_points_px: list[list[float]] | None = None
    tags: list[TagInfo] | None = None
    time: float | None = None
    method: str | None = Field(None, description="'points' for a calibration from clicked points, 'arm-camera' from the arm's gripper tag (tags otherwise)")
    points: dict | None = Field(None, description="clicked-point fit: homography, reprojection and per-point errors (px)")


class TargetCheckResponse(Wire):
    """A grab or drop target checked as the command would plan it, nothing moved (POST /api/grab/check,
    /api/drop/check): what it would do. A refusal is the command's own error (422 unreachable/unsafe, 409)."""

    ok: bool = True
    detail: str = Field(description="what the command would do, e.g. 'grab large red block at (120, 250) mm'")


class PixelToWorldResponse(Wire):
    """on: 'depth' (the newest frame, the robot's own readings left out), 'remembered' (under the arm: the
    depth last seen there without it) or 'board' (the viewing ray meets z = 0)."""

    position_m: Vector3
    on: Literal["board", "depth", "remembered"]
    depth_mm: float | None = Field(None, description="the raw depth reading at the pixel, mm (0: no reading; None: no depth image)")
