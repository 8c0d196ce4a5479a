"""Pydantic models of the wire protocol: REST bodies and responses, websocket messages.

Field names carry their units (SI). Requests forbid unknown fields and NaN/infinity, so malformed
input is refused with a clear 422 before the station sees it. web/js/wire_types.js is generated from
these models and server/program_models.py's (server/gen_wire_types.py).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from armlab.scene import COLORS, OBJECT_TYPES, SIZES
from armlab.scene import JOBS as SCENE_JOBS

Vector3 = list[float]
View = Literal["color", "depth", "topdown"]
Layer = Literal["tags", "detections", "grid"]
ERROR_CODES = (
    "wrong_state",
    "unreachable",
    "unsafe",
    "invalid",
    "not_found",
    "not_calibrated",
    "unauthorized",
    "forbidden",
    "not_controller",
    "needs_confirmation",
    "device",
    "internal",
)

# Sanity bounds of request values, stated in the OpenAPI schema. The station applies the real limits
# (joint limits, reach, config max_moving_time_s) on top; these only keep absurd numbers out.
ANGLE_LIMIT_RAD = 2.0 * math.pi
POSITION_LIMIT_M = 5.0  # the workcell is ~1 m across; scene objects are refused beyond 5 m too
MOVING_TIME_LIMIT_S = 3600.0
PIXEL_LIMIT = 100_000.0
SQLITE_INTEGER_MAX = 2**63 - 1  # program ids are SQLite INTEGERs

Angle = Annotated[float, Field(ge=-ANGLE_LIMIT_RAD, le=ANGLE_LIMIT_RAD, description="radians, |angle| <= 2π")]
Coordinate = Annotated[float, Field(ge=-POSITION_LIMIT_M, le=POSITION_LIMIT_M, description="metres, |value| <= 5")]
Position = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
MovingTime = Annotated[float, Field(gt=0.0, le=MOVING_TIME_LIMIT_S, description="seconds; the station refuses more than its configured maximum")]
Velocity = Annotated[float, Field(ge=-ANGLE_LIMIT_RAD, le=ANGLE_LIMIT_RAD, description="rad/s, |value| <= 2π; the station applies the joint limits")]
Pixel = Annotated[float, Field(ge=0.0, le=PIXEL_LIMIT, description="pixel coordinate in the colour image")]
SpeedPercent = Annotated[float, Field(ge=10.0, le=100.0, description="speed override, % of the configured speed (10-100)")]
ProgramId = Annotated[int, Field(ge=0, le=SQLITE_INTEGER_MAX, description="a program id (SQLite integer)")]


class Request(BaseModel):
    """Base of every request: strict types (no bool/number/string coercion), no unknown fields, no NaN/inf."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


class Wire(BaseModel):
    model_config = ConfigDict(allow_inf_nan=True)


# Requests -----------------------------------------------------------------------------------------


class JointsRequest(Request):
    q_rad: list[Angle] = Field(min_length=1, max_length=12, description="joint positions, radians, in joint_names order")
    moving_time_s: MovingTime | None = Field(None, description="move duration; None = as fast as the limits allow")


class PoseRequest(Request):
    position_m: Position = Field(description="gripper point in the world (board) frame")
    pitch_rad: Angle | None = Field(None, description="approach angle below horizontal; +π/2 = straight down; None = steepest")
    yaw_rad: Angle | None = Field(None, description="block yaw in the world frame the fingers align with")
    moving_time_s: MovingTime | None = None


class PoseNameRequest(Request):
    """Optional body of /api/arm/home and /api/arm/sleep."""

    moving_time_s: MovingTime | None = None


class TorqueRequest(Request):
    enabled: bool
    confirm: bool = Field(False, description="torque off outside teach lets the arm fall: needs confirm: true")


class JogRequest(Request):
    """Hold-to-run jog: joint velocities kept for jog_hold_s after each heartbeat (this request, or a
    heartbeat), then the arm ramps to rest by itself."""

    velocity_rad_s: list[Velocity] = Field(min_length=1, max_length=12, description="joint velocities, joint_names order; zeros stop")
    speed_percent: SpeedPercent = 100.0


STEP_DISTANCE_LIMIT_M = 0.1
STEP_ANGLE_LIMIT_RAD = math.pi / 4


class StepRequest(Request):
    """A jog step of the gripper: distance_m along world x|y|z keeping its pitch and yaw (within 0.5°,
    the point within 1 mm of the line), or angle_rad of pitch (about the gripper point) or wrist roll."""

    axis: Literal["x", "y", "z", "pitch", "roll"]
    distance_m: float | None = Field(
        None, ge=-STEP_DISTANCE_LIMIT_M, le=STEP_DISTANCE_LIMIT_M, description="metres along the world axis (x, y, z); non-zero"
    )
    angle_rad: float | None = Field(
        None, ge=-STEP_ANGLE_LIMIT_RAD, le=STEP_ANGLE_LIMIT_RAD, description="radians of pitch (+ = down) or roll; non-zero"
    )
    speed_percent: SpeedPercent = 100.0

    @model_validator(mode="after")
    def _one_amount(self) -> "StepRequest":
        linear = self.axis in ("x", "y", "z")
        amount, other = (self.distance_m, self.angle_rad) if linear else (self.angle_rad, self.distance_m)
        needed = "distance_m" if linear else "angle_rad"
        if other is not None or amount is None:
            raise ValueError(f"a {self.axis} step needs {needed} alone")
        if amount == 0.0:
            raise ValueError(f"{needed} must not be zero")
        return self


class GripperRequest(Request):
    action: Literal["grasp", "release"]


class PixelRequest(Request):
    u: Pixel = Field(description="pixel column in the colour image")
    v: Pixel = Field(description="pixel row in the colour image")


class ClickedPoint(Request):
    pixel: list[float] = Field(min_length=2, max_length=2, description="(u, v) in the colour image")
    world_m: list[float] = Field(min_length=2, max_length=3, description="its known world point: (x, y) on the board or (x, y, z)")


class PointsCalibrationRequest(Request):
    """Calibration without tags: >= 4 clicked pixels whose world points are known (board grid corners or typed)."""

    points: list[ClickedPoint] = Field(min_length=1, max_length=200)


class TargetRequest(Request):
    """A grab/drop target: a world point, or a pixel of the colour image (exactly one)."""

    position_m: Position | None = None
    u: Pixel | None = None
    v: Pixel | None = None

    @model_validator(mode="after")
    def _one_target(self) -> "TargetRequest":
        has_pixel = self.u is not None or self.v is not None
        if has_pixel and (self.u is None or self.v is None):
            raise ValueError("a pixel target needs both u and v")
        if has_pixel == (self.position_m is not None):
            raise ValueError("give either position_m or u and v, not both or neither")
        return self


class SceneObjectRequest(Request):
    """One object of an explicit scene, in the ground-truth format (quat_wxyz wins over yaw_rad)."""

    id: str = Field(pattern=r"^[A-Za-z0-9_.:-]{1,64}$")
    type: Literal[OBJECT_TYPES]  # type: ignore[valid-type]
    color: Literal[COLORS]  # type: ignore[valid-type]
    size: Literal[SIZES] | None = Field(None, description="blocks: large (default) or small; distractors: None = large")  # type: ignore[valid-type]
    position_m: Position = Field(description="body centre, world frame")
    yaw_rad: Angle | None = None
    quat_wxyz: Annotated[list[Annotated[float, Field(ge=-1e6, le=1e6)]], Field(min_length=4, max_length=4)] | None = Field(
        None, description="orientation (w, x, y, z), non-zero; normalised by the station"
    )
    aruco_id: int | None = Field(None, ge=0, le=249, description="ArUco tag (DICT_4X4_250) on a block's top face")


class CameraBumpRequest(Request):
    """Simulation only: knock the camera mount, as a bump on the rig would (the camera's own OpenCV frame)."""

    translation_m: Annotated[list[Annotated[float, Field(ge=-0.05, le=0.05)]], Field(min_length=3, max_length=3)] = Field(
        description="shift of the camera, metres (each |value| <= 0.05)")
    rotation_rad: Annotated[list[Annotated[float, Field(ge=-0.1, le=0.1)]], Field(min_length=3, max_length=3)] = Field(
        description="rotation vector of the turn, radians (each |value| <= 0.1)")


class SceneRequest(Request):
    """A generated competition scene (event, level, seed) or explicit objects (ground-truth format)."""

    event: Literal[tuple(SCENE_JOBS)] | None = Field(None, description="a competition event or another job with a scene generator")  # type: ignore[valid-type]
    level: int | None = Field(None, ge=1, le=3)
    seed: int | None = Field(None, ge=0, le=2**32 - 1)
    objects: list[SceneObjectRequest] | None = Field(None, max_length=100)

    @model_validator(mode="after")
    def _one_kind(self) -> "SceneRequest":
        if (self.event is None) == (self.objects is None):
            raise ValueError("give either event (with level and seed) or objects")
        return self


# Responses ----------------------------------------------------------------------------------------


class ErrorBody(Wire):
    code: str
    message: str
    allowed: list[str] | None = None


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


class Status(Wire):
    state: Literal["idle", "calibrate", "teach", "repeat", "click_grab", "click_drop", "auto_sort", "estop", "fault"]
    detail: str
    joints_rad: list[float]
    joint_names: list[str]
    joint_limits_rad: list[list[float]] = Field(description="[lower, upper] per joint")
    gripper: GripperStatus
    gripper_pose: GripperPose
    moving: bool
    torque_enabled: bool = Field(True, description="motor torque on (the arm holds); off = limp, it falls unless held")
    calibrated: bool
    camera_warning: str | None = Field(None, description='"camera moved: recalibrate (...)" when the board tags no longer sit where the calibration puts them')
    calibration_state: Literal["checking", "trusted", "rejected"] | None = Field(
        None, description="trusted: in use; checking: restored at start, not used until the board tags confirm it; rejected: restored but the camera moved since (recalibrate); None: no calibration")
    self_recalibrate: bool = Field(False, description="the station recalibrates itself from the board tags when idle once the camera moved (PUT /api/calibration/settings)")
    backend: Literal["sim", "real"]
    controller: str | None = Field(description="who holds the control lease (None: free); only it may command")
    controller_since_s: float | None = Field(None, description="when it took control (time.time())")
    devices_lost: dict[str, str] = Field(default_factory=dict, description="devices not answering, with the reason")
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
    grid_points_px: list[list[float]] | None = None
    tags: list[TagInfo] | None = None
    time: float | None = None
    method: str | None = Field(None, description="'points' for a calibration from clicked points (tags otherwise)")
    points: dict | None = Field(None, description="clicked-point fit: homography, reprojection and per-point errors (px)")


class PixelToWorldResponse(Wire):
    """on: 'depth' (the newest frame, the robot's own readings left out), 'remembered' (under the arm: the
    depth last seen there without it) or 'board' (the viewing ray meets z = 0)."""

    position_m: Vector3
    on: Literal["board", "depth", "remembered"]
    depth_mm: float | None = Field(None, description="the raw depth reading at the pixel, mm (0: no reading; None: no depth image)")


# Websocket messages ------------------------------------------------------------------------------


class FrameHeader(Wire):
    """Header of a binary frame: [uint32 LE header length N][N bytes of this JSON][JPEG bytes]."""

    type: Literal["frame"] = "frame"
    seq: int
    capture_time_s: float = Field(description="time.time() at capture")
    width: int
    height: int
    view: View


class TelemetryMessage(Status):
    type: Literal["telemetry"] = "telemetry"
    detections: list[Detection]
    detections_stale: bool = False


class EventMessage(Wire):
    type: Literal["event"] = "event"
    level: Literal["info", "warn", "error"]
    message: str
    time_s: float


class CalibrationMessage(CalibrationInfo):
    type: Literal["calibration"] = "calibration"


class GridInfo(Wire):
    x_m: list[float] = Field(description="first and last grid point x, metres")
    y_m: list[float] = Field(description="first and last grid point y, metres")
    step_m: float


class BoardInfo(Wire):
    x_range_m: list[float] = Field(description="[x_min, x_max] of the board, world frame, metres")
    y_range_m: list[float] = Field(description="[y_min, y_max] of the board, world frame, metres")
    grid: GridInfo


class BoardTagsInfo(Wire):
    family: str
    size_m: float
    centres_m: dict[str, list[float]] = Field(description="tag id -> [x, y] of its centre, metres")


class BinInfo(Wire):
    x_range_m: list[float]
    y_range_m: list[float]


class WorkcellInfo(Wire):
    """The workcell's geometry (config/workcells/<name>.yaml), sent once in the hello."""

    name: str
    board: BoardInfo
    board_tags: BoardTagsInfo
    block_edges_m: dict[str, float] = Field(description="block size (large, small) -> cube edge, metres")
    places_m: dict[str, list[float]] = Field(description="sort_by_tag place -> [x, y], metres")
    feeder_spot_m: list[float] = Field(description="to_the_sky feed spot [x, y], metres")
    bin: BinInfo


class ArmInfo(Wire):
    """The station's arm and gripper (armlab.station.arm_info), sent once in the hello: the page builds its
    jog sliders, joint readouts, plot and teach table from these, never from names of its own."""

    name: str = Field(description="config/arms/<name>.yaml")
    vendor: str | None = Field(None, description="who makes the arm (interbotix, universal_robots); None = not said")
    joint_names: list[str]
    joint_limits_rad: list[list[float]] = Field(description="[lower, upper] per joint, joint_names order")
    velocity_limits_rad_s: list[float]
    home_rad: list[float]
    gripper_type: Literal["fingers", "suction"]
    full_pose: bool = Field(description="Cartesian moves keep the tool's whole orientation (six joints or more), else pitch and yaw")


class LimitsInfo(Wire):
    """Limits of operator inputs, from the station's config (the page checks inputs against these)."""

    max_moving_time_s: float = Field(description="longest manual move accepted (moving_time_s is in (0, this])")


class HelloMessage(Wire):
    type: Literal["hello"] = "hello"
    server_time_s: float
    can_control: bool
    controller: str | None = Field(None, description="this session's controller name (the lease holder's name when it commands)")
    backend: Literal["sim", "real"]
    workcell: WorkcellInfo
    arm: ArmInfo
    limits: LimitsInfo | None = None


class AckMessage(Request):
    type: Literal["ack"]
    seq: int


class ViewMessage(Request):
    type: Literal["view"]
    view: View = "color"
    layers: list[Layer] = []


class CommandMessage(Request):
    type: Literal["command"]
    name: Literal["estop", "reset", "cancel", "take_control", "release_control"]


class HeartbeatMessage(Request):
    """The controlling page is still there: keeps its hold-to-run jog going for another jog_hold_s."""

    type: Literal["heartbeat"]


WIRE_MODELS: tuple[type[BaseModel], ...] = (
    ErrorBody,
    ErrorResponse,
    GripperStatus,
    GripperPose,
    JobInfo,
    JobResponse,
    Status,
    Detection,
    DetectionsResponse,
    TagInfo,
    CalibrationInfo,
    PixelToWorldResponse,
    JointsRequest,
    PoseRequest,
    PoseNameRequest,
    TorqueRequest,
    JogRequest,
    StepRequest,
    GripperRequest,
    PixelRequest,
    TargetRequest,
    SceneObjectRequest,
    SceneRequest,
    FrameHeader,
    TelemetryMessage,
    EventMessage,
    CalibrationMessage,
    GridInfo,
    BoardInfo,
    BoardTagsInfo,
    BinInfo,
    WorkcellInfo,
    LimitsInfo,
    HelloMessage,
    AckMessage,
    ViewMessage,
    CommandMessage,
    HeartbeatMessage,
)


# Autonomous jobs (server/routes/auto.py) ---------------------------------------------------------

AUTO_LEVEL_LIMIT = 100  # sanity bound; the job's own levels (GET /api/auto/jobs) are checked by the station
AUTO_PARAMS_MAX = 32


class AutoRequest(Request):
    """Start an autonomous job: a name from GET /api/auto/jobs, one of its levels, its parameters."""

    job: str = Field(min_length=1, max_length=64, description="job name (GET /api/auto/jobs)")
    level: int | None = Field(None, ge=0, le=AUTO_LEVEL_LIMIT, description="one of the job's levels; None = its highest")
    params: dict[Annotated[str, Field(max_length=64)], Any] | None = Field(
        None, max_length=AUTO_PARAMS_MAX, description="job parameters by name, each of the type GET /api/auto/jobs gives"
    )


class AutoParam(Wire):
    name: str
    type: str = Field(description="Python type name: int, float, str, bool, list, ...")


class AutoJobInfo(Wire):
    name: str
    levels: list[int] = Field(description="[] = the job has no levels")
    summary: str
    params: list[AutoParam]
    judged: bool = Field(description="a competition event (DESIGN §7): the simulation scores it with the judge")
    scored: bool = Field(description="the simulation scores it: the judge (§7), else the job's own scorer")
    scene: bool = Field(description="POST /api/sim/scene can generate its starting scene")
    time_limit_s: float | None = Field(None, description="the event's time limit, simulated seconds")


class AutoJobsResponse(Wire):
    data: list[AutoJobInfo]
    count: int


class TaskProgress(Wire):
    """job.extra.task of a running autonomous job (also on the websocket's telemetry)."""

    done: int
    left: int
    step: str
    attempts: int
    failures: list[str]
    moves: int
    next_block: Detection | None = Field(None, description="the block being moved (a detection)")
    next_target_m: Vector3 | None = Field(None, description="where it goes: bottom-centre x, y and surface z, world frame")


class ScoreRule(Wire):
    rule: str
    points: int
    detail: str
    object_ids: list[str]


class AutoScore(Wire):
    points: int
    max_points: int
    within_limit: bool
    full: bool
    time_limit_s: float
    breakdown: list[ScoreRule]


class AutoScoreResponse(Wire):
    """The judge's score of the last autonomous job started over the API (simulation only)."""

    job_id: str
    job: str
    level: int | None
    state: Literal["running", "succeeded", "failed", "cancelled"]
    final: bool = Field(description="True once the job has ended and its final ground truth was scored")
    sim_time_s: float = Field(description="simulated seconds from the job's start to its end (so far, while running)")
    score: AutoScore | None = Field(None, description="None while running, or for a job the judge does not score")
    note: str = ""


class AutoResponse(Wire):
    job: JobInfo
    score: AutoScoreResponse | None = Field(None, description="with ?wait=true in the simulation: the final score")


WIRE_MODELS = (
    *WIRE_MODELS,
    AutoRequest,
    AutoParam,
    AutoJobInfo,
    AutoJobsResponse,
    TaskProgress,
    ScoreRule,
    AutoScore,
    AutoScoreResponse,
    AutoResponse,
)
