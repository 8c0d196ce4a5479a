"""Pydantic models of the wire protocol: REST bodies and responses, websocket messages.

Field names carry their units (SI). Requests forbid unknown fields and NaN/infinity, so malformed
input is refused with a clear 422 before the station sees it. The models live by resource: the base
types in server/wire_base.py, the arm's requests in server/arm_models.py, the scene's in
server/scene_models.py, REST responses in server/response_models.py, websocket messages in
server/stream_models.py, autonomous jobs in server/auto_models.py (programs: server/program_models.py);
this module defines the calibration and click-target requests and gathers (re-exports) the rest, with
WIRE_MODELS, the list web/js/wire_types.js is generated from (server/gen_wire_types.py).
"""

from __future__ import annotations

from pydantic import BaseModel, Field, model_validator

# Re-exported: the routes and the generator import every wire model from here.
from server.arm_models import (
    STEP_ANGLE_LIMIT_RAD,
    STEP_DISTANCE_LIMIT_M,
    CartesianJogRequest,
    GripperRequest,
    JogRequest,
    JointsRequest,
    MoveCheck,
    PoseNameRequest,
    PoseRequest,
    StepRequest,
    TorqueRequest,
)
from server.auto_models import (
    AUTO_LEVEL_LIMIT,
    AUTO_PARAMS_MAX,
    AutoJobInfo,
    AutoJobsResponse,
    AutoParam,
    AutoRequest,
    AutoResponse,
    AutoScore,
    AutoScoreResponse,
    ScoreRule,
    TaskProgress,
)
from server.colors_models import COLOR_WIRE_MODELS
from server.plan_models import PLAN_WIRE_MODELS
from server.recording_models import RECORDING_WIRE_MODELS
from server.response_models import (
    CalibrationInfo,
    Detection,
    DetectionsResponse,
    ErrorBody,
    ErrorResponse,
    GripperPose,
    GripperStatus,
    JobInfo,
    JobResponse,
    PixelToWorldResponse,
    Status,
    TagInfo,
    TargetCheckResponse,
)
from server.scene_models import CameraBumpRequest, SceneObjectRequest, SceneRequest
from server.stream_models import (
    AckMessage,
    ArmInfo,
    BinInfo,
    BoardInfo,
    BoardTagsInfo,
    CalibrationMessage,
    CommandMessage,
    EventMessage,
    FrameHeader,
    GridInfo,
    HeartbeatMessage,
    HelloMessage,
    JogCartesianMessage,
    JogMessage,
    JogReplyMessage,
    JogStopMessage,
    LimitsInfo,
    TelemetryMessage,
    ViewMessage,
    WorkcellInfo,
)
from server.wire_base import (
    ANGLE_LIMIT_RAD,
    ERROR_CODES,
    MOVING_TIME_LIMIT_S,
    PIXEL_LIMIT,
    POSITION_LIMIT_M,
    SQLITE_INTEGER_MAX,
    Angle,
    Coordinate,
    Layer,
    MovingTime,
    Pixel,
    Position,
    ProgramId,
    Request,
    SpeedPercent,
    Vector3,
    Velocity,
    View,
    Wire,
)

# Calibration and click targets (server/routes/calibration.py, jobs.py) -----------------------------


class PixelRequest(Request):
    u: Pixel = Field(description="pixel column in the colour image")
    v: Pixel = Field(description="pixel row in the colour image")


class ClickedPoint(Request):
    pixel: list[Pixel] = Field(min_length=2, max_length=2, description="(u, v) in the colour image")
    world_m: list[Coordinate] = Field(min_length=2, max_length=3, description="its known world point: (x, y) on the board or (x, y, z)")


class PointsCalibrationRequest(Request):
    """Calibration without tags: >= 4 clicked pixels whose world points are known (board grid corners or typed)."""

    points: list[ClickedPoint] = Field(min_length=1, max_length=200)

    @model_validator(mode="after")
    def _one_world_dimension(self) -> PointsCalibrationRequest:
        if len({len(point.world_m) for point in self.points}) > 1:
            raise ValueError("points: world_m must be (x, y) for every point or (x, y, z) for every point, not a mix")
        return self


class TargetRequest(Request):
    """A grab/drop target: a world point, or a pixel of the colour image (exactly one)."""

    position_m: Position | None = None
    u: Pixel | None = None
    v: Pixel | None = None

    @model_validator(mode="after")
    def _one_target(self) -> TargetRequest:
        has_pixel = self.u is not None or self.v is not None
        if has_pixel and (self.u is None or self.v is None):
            raise ValueError("a pixel target needs both u and v")
        if has_pixel == (self.position_m is not None):
            raise ValueError("give either position_m or u and v, not both or neither")
        return self


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
    TargetCheckResponse,
    JointsRequest,
    PoseRequest,
    MoveCheck,
    PoseNameRequest,
    TorqueRequest,
    JogRequest,
    CartesianJogRequest,
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
    JogMessage,
    JogCartesianMessage,
    JogStopMessage,
    JogReplyMessage,
)

WIRE_MODELS = (
    *WIRE_MODELS,
    *COLOR_WIRE_MODELS,
    *RECORDING_WIRE_MODELS,
    *PLAN_WIRE_MODELS,
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
