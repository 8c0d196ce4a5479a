"""Websocket messages (server/stream.py): the frame header, telemetry, events, the hello and what the page sends."""

from __future__ import annotations

from typing import Literal, get_args

from pydantic import Field

from server.arm_models import CartesianJogRequest, JogRequest
from server.response_models import CalibrationInfo, Detection, Status
from server.wire_base import Layer, Request, View, Wire


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
    """An operator event. The page acts on `kind` (armlab.station.slots.EventLog.KINDS), never on the text."""

    type: Literal["event"] = "event"
    level: Literal["info", "warn", "error"]
    kind: Literal["general", "scene"] = Field(description="what happened, for a client to act on; 'general': for people only")
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
    gripper_type: Literal["fingers", "suction", "none"]
    full_pose: bool = Field(description="Cartesian moves keep the tool's whole orientation (six joints or more), else pitch and yaw")
    has_arm: bool = Field(True, description="False: a station with no arm (armlab serve --arm none), perception only; no joints")
    reason: str | None = Field(None, description="why the arm's panels are off (a station with no arm)")


class LimitsInfo(Wire):
    """Limits of operator inputs, from the station's config (the page checks inputs against these)."""

    max_moving_time_s: float = Field(description="longest manual move accepted (moving_time_s is in (0, this])")
    jog_max_speed_rad_s: float | None = Field(None, description="fastest hold-to-run joint jog at 100 % (each joint's own limit caps it)")
    jog_hold_s: float | None = Field(None, description="a hold-to-run jog brakes this long after the controller's last heartbeat")
    jog_max_speed_m_s: float | None = Field(None, description="fastest hold-to-run Cartesian jog of the gripper point at 100 %")
    jog_accel_m_s2: float | None = Field(None, description="the Cartesian jog's ramp (and braking) acceleration")


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


JogId = Field(None, ge=0, le=2**31 - 1, description="echoed in the jog_reply, so the page knows which request it answers")


class JogMessage(JogRequest):
    """Start (or keep going) a hold-to-run joint jog, as POST /api/arm/jog; answered by a jog_reply."""

    type: Literal["jog"]
    id: int | None = JogId


class JogCartesianMessage(CartesianJogRequest):
    """Start (or keep going) a hold-to-run Cartesian jog, as POST /api/arm/jog/cartesian; answered by a jog_reply."""

    type: Literal["jog_cartesian"]
    id: int | None = JogId


class JogStopMessage(Request):
    """The held button or key was let go: this session's controller's jog ramps down now (POST /api/arm/jog/stop)."""

    type: Literal["jog_stop"]
    id: int | None = JogId


class JogReplyMessage(Wire):
    """The answer to a jog, jog_cartesian or jog_stop message: ok, or the HTTP status and error code the REST route
    would give (422 invalid / unreachable / unsafe, 409 not_controller / wrong_state, ...) and the reason."""

    type: Literal["jog_reply"] = "jog_reply"
    id: int | None = None
    ok: bool
    status_code: int = Field(200, description="what the REST route answers for the same request")
    code: str | None = Field(None, description="the error code (ErrorBody.code) when not ok")
    message: str | None = None


# Every websocket message each side sends, one model per `type` (the generator and stream.py read these).
SERVER_MESSAGES = (FrameHeader, TelemetryMessage, EventMessage, CalibrationMessage, HelloMessage, JogReplyMessage)
CLIENT_MESSAGES = (AckMessage, ViewMessage, CommandMessage, HeartbeatMessage, JogMessage, JogCartesianMessage, JogStopMessage)


def message_type(model: type[Wire]) -> str:
    """The `type` a websocket message model carries (its field's one Literal value)."""
    (value,) = get_args(model.model_fields["type"].annotation)
    return value
