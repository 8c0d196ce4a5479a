"""Wire models of teach, taught programs and repeat (issue 9): requests strict like every request,
responses documenting what the routes return. Generated into web/js/wire_types.js with server/models.py's."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Discriminator, Field, Tag, field_validator, model_validator

from armlab.store import MAX_PROGRAM_NAME_CHARS
from armlab.store.program_tree import MAX_DEPTH, MAX_LABEL_CHARS, MAX_LOOP_COUNT
from server.models import Angle, MovingTime, Request, Wire

DWELL_LIMIT_S = 3600.0
WAYPOINTS_LIMIT = 1000
IMPORT_TEXT_LIMIT = 1_000_000
IMPORT_FILE_LIMIT = 200_000_000  # an uploaded bag
CYCLES_LIMIT = 100_000

Speed = Annotated[float, Field(ge=10.0, le=100.0, description="speed override, % of full speed (10-100)")]
Dwell = Annotated[float, Field(ge=0.0, le=DWELL_LIMIT_S, description="seconds to hold still at the waypoint")]
ProgramName = Annotated[str, Field(min_length=1, max_length=MAX_PROGRAM_NAME_CHARS)]


# Requests -----------------------------------------------------------------------------------------


class TeachStartRequest(Request):
    """Optional body of POST /api/teach/start: an unsaved draft (from a stopped or killed station) is resumed unless discard_draft."""

    discard_draft: bool = Field(False, description="start with no waypoints, dropping an unsaved draft")


class TeachRecordRequest(Request):
    """Optional body of POST /api/teach/record: the waypoint's dwell and the time of the move into it."""

    dwell_s: Dwell = 0.0
    moving_time_s: MovingTime | None = Field(None, description="least time of the move into this waypoint at 100 %; None = as fast as allowed")


class ContinuousRequest(Request):
    """POST /api/teach/continuous: trajectory mode, recording the pose at rate_hz while it changes."""

    rate_hz: float = Field(ge=0.5, le=20.0, description="records per second (0.5-20)")
    min_change_rad: float = Field(0.01, gt=0.0, le=1.0, description="record only when a joint moved this much (or the gripper changed)")


class ContinuousResponse(Wire):
    recording: bool
    rate_hz: float | None = None
    recorded: int = Field(description="waypoints this recording added")
    count: int = Field(description="waypoints in the draft now")


class TeachStopRequest(Request):
    name: ProgramName


class WaypointRequest(Request):
    """A waypoint as sent in a program edit: joints (rad, joint_names order), gripper, dwell, move time."""

    joints_rad: list[Angle] = Field(min_length=1, max_length=12)
    gripper: Literal["grasp", "release"]
    dwell_s: Dwell = 0.0
    moving_time_s: MovingTime | None = None
    gripper_position_m: list[Annotated[float, Field(ge=-5.0, le=5.0)]] | None = Field(
        None, max_length=3, description="read-only (computed from joints_rad): accepted so a waypoint read can be sent back, ignored"
    )


class WaypointStepRequest(WaypointRequest):
    """A waypoint in a step tree ('kind' may be left out: an item without it is a waypoint)."""

    kind: Literal["waypoint"] = "waypoint"


class WaitStepRequest(Request):
    """Hold still at the waypoint before it for `seconds` (added to its dwell)."""

    kind: Literal["wait"]
    seconds: Annotated[float, Field(gt=0.0, le=DWELL_LIMIT_S, description="seconds to wait (above 0, at most 3600)")]


class GripperStepRequest(Request):
    """Open or close the gripper at the pose of the waypoint before it."""

    kind: Literal["gripper"]
    action: Literal["open", "close"]


class LoopStepRequest(Request):
    """Run `body` `count` times (1-1000)."""

    kind: Literal["loop"]
    count: int = Field(ge=1, le=MAX_LOOP_COUNT, description=f"how many times the body runs (1-{MAX_LOOP_COUNT})")
    body: list[StepRequest] = Field(min_length=1, max_length=WAYPOINTS_LIMIT)


class GroupStepRequest(Request):
    """A labelled group of steps (run once)."""

    kind: Literal["group"]
    label: str = Field(min_length=1, max_length=MAX_LABEL_CHARS)
    body: list[StepRequest] = Field(min_length=1, max_length=WAYPOINTS_LIMIT)


def _step_kind(value: Any) -> str:
    kind = value.get("kind", "waypoint") if isinstance(value, dict) else getattr(value, "kind", "waypoint")
    return kind if isinstance(kind, str) else "invalid"


StepRequest = Annotated[
    (Annotated[WaypointStepRequest, Tag("waypoint")] | Annotated[WaitStepRequest, Tag("wait")]
     | Annotated[GripperStepRequest, Tag("gripper")] | Annotated[LoopStepRequest, Tag("loop")]
     | Annotated[GroupStepRequest, Tag("group")]),
    Discriminator(_step_kind),
]
LoopStepRequest.model_rebuild()
GroupStepRequest.model_rebuild()


def too_deep(steps: list, path: str = "steps", level: int = 1) -> str | None:
    """The path of the first loop or group nested deeper than MAX_DEPTH, or None."""
    for index, step in enumerate(steps):
        body = getattr(step, "body", None)
        if body is None:
            continue
        if level > MAX_DEPTH:
            return f"{path}[{index}]"
        found = too_deep(body, f"{path}[{index}].body", level + 1)
        if found:
            return found
    return None


class ProgramUpdateRequest(Request):
    """PATCH /api/programs/{id}: a new name and/or the whole new waypoint list (reorder, edit a value,
    insert or delete a waypoint or a gripper step: send the list as it should be), or the whole step tree
    (waypoints, waits, gripper steps, loops, labelled groups; at most 4 deep, at most 1000 waypoints once
    expanded). Checked against the joint limits and the table before anything is stored."""

    name: ProgramName | None = None
    waypoints: list[WaypointRequest] | None = Field(None, min_length=1, max_length=WAYPOINTS_LIMIT)
    steps: list[StepRequest] | None = Field(None, min_length=1, max_length=WAYPOINTS_LIMIT,
                                            description="the program's step tree (replaces waypoints; a tree of waypoints only is a flat program)")

    @field_validator("steps")
    @classmethod
    def _not_too_deep(cls, steps: list | None) -> list | None:
        where = too_deep(steps or [])
        if where:
            raise ValueError(f"{where}: loops and groups are nested more than {MAX_DEPTH} deep")
        return steps

    @model_validator(mode="after")
    def _something(self) -> ProgramUpdateRequest:
        if self.name is None and self.waypoints is None and self.steps is None:
            raise ValueError("give name and/or waypoints or steps")
        if self.waypoints is not None and self.steps is not None:
            raise ValueError("give waypoints or steps, not both")
        return self


class DuplicateRequest(Request):
    name: ProgramName | None = Field(None, description="the copy's name; None = '<name> (copy)'")


class ImportRequest(Request):
    """POST /api/programs/import: a file's text as exported (JSON or CSV `t_s, q1..qn, gripper`)."""

    format: Literal["json", "csv"]
    content: str = Field(max_length=IMPORT_TEXT_LIMIT, description="the file's text")
    name: ProgramName | None = Field(None, description="the program's name; None = the JSON's name, else 'imported'")


class RepeatRequest(Request):
    cycles: int | None = Field(1, ge=1, le=CYCLES_LIMIT, description="how many cycles; None = until stopped (cancel)")
    speed_percent: Speed | None = Field(None, description="speed override (10-100 %); None = the station's (GET /api/speed); a "
                                        "number becomes the station's override")


class SpeedRequest(Request):
    """PUT /api/speed, PATCH /api/jobs/current: the station's speed override (takes effect at once, smoothly)."""

    speed_percent: Speed


class SpeedResponse(Wire):
    """GET/PUT /api/speed: the speed override in force."""

    speed_percent: float = Field(description="% of full speed (10-100), applied to every motion the station plans")


# Responses ----------------------------------------------------------------------------------------


class WaypointInfo(Wire):
    joints_rad: list[float]
    gripper: Literal["grasp", "release"]
    dwell_s: float = 0.0
    moving_time_s: float | None = None
    gripper_position_m: list[float] | None = Field(
        None, description="the gripper point at these joints (FK), world frame: project it through the calibration to draw the path"
    )


class ProgramInfo(Wire):
    id: int
    name: str
    created_s: float
    updated_s: float | None = None
    arm: str | None = Field(None, description="the arm it was taught on (None: saved before programs had an arm)")
    workcell: str | None = Field(None, description="the workcell it was taught in (None: saved before programs had one)")
    waypoints: list[WaypointInfo] = Field(description="the flat sequence repeat runs (a step tree expanded)")
    steps: list[dict[str, Any]] | None = Field(None, description="the step tree (waypoints, wait, gripper, loop, group); None: waypoints only")


class ImportFileResponse(ProgramInfo):
    """POST /api/programs/import/file: the stored program and how the file became it."""

    notes: list[str] = Field([], description="what the import read and did, one line each (topic, gripper source, thinning)")
    clamped_rad: dict[str, float] = Field({}, description="joints clamped into their limits: the largest correction, rad")
    clamped_samples: int = Field(0, description="samples clamped (only with clamp_rad)")
    samples: int = Field(0, description="joint samples read (0: a CSV or JSON program)")


class OtherPrograms(Wire):
    """Programs in the same database that belong to another arm or workcell (not listed: their joints mean nothing here)."""

    arm: str | None = Field(description="None: saved before programs had an arm, with another number of joints")
    workcell: str | None
    count: int


class ProgramsResponse(Wire):
    """GET /api/programs: this station's arm's (and workcell's) programs."""

    data: list[ProgramInfo]
    count: int
    skipped: list[str] = Field([], description="damaged rows left out of data, one line each (also logged)")
    others_count: int = Field(0, description="programs of other arms or workcells in the same database (not in data)")
    others: list[OtherPrograms] = Field([], description="those programs, counted by arm and workcell")


class TeachRecordResponse(WaypointInfo):
    """The recorded waypoint (committed to the draft on disk before this answer) and the draft's size."""

    count: int = Field(description="waypoints in the draft now")


class TeachUndoResponse(Wire):
    removed: WaypointInfo | None = Field(None, description="the waypoint taken off the end (None: the draft was empty)")
    count: int


class TeachDraftResponse(Wire):
    """The waypoints recorded and not yet saved (kept on disk: a restarted station resumes them on teach/start)."""

    waypoints: list[WaypointInfo]
    count: int
    skipped: list[str] = []


class RepeatProgress(Wire):
    """job.extra.repeat of a running repeat (also on the websocket's telemetry)."""

    program_id: int
    cycle: int = Field(description="the cycle running, 1-based")
    cycles: int | None = Field(description="None = until stopped")
    waypoint: int = Field(description="the waypoint last reached, 1-based")
    waypoints: int
    phase: Literal["ease in", "cycle", "home", "paused"]
    paused: bool
    speed_percent: float
    cycle_s: float = Field(description="one cycle at this speed, seconds")
    time_left_s: float | None = Field(description="None while easing in or when repeating until stopped")
    last_cycle_times_s: list[float] = Field(description="the durations of the last cycles (at most 5)")
    blended_runs: int = Field(description="runs that pass through waypoints without stopping")
    runs: int


class TraceResponse(Wire):
    """GET /api/jobs/current/trace: commanded and measured joints over the last complete cycle of the
    repeat (the running one until a cycle has completed). samples: [t_s, commanded × dof, measured × dof]."""

    job_id: str
    cycle: int
    complete: bool
    joint_names: list[str]
    columns: list[str]
    samples: list[list[float]]


PROGRAM_WIRE_MODELS = (
    TeachStartRequest,
    TeachRecordRequest,
    TeachStopRequest,
    ContinuousRequest,
    ContinuousResponse,
    WaypointRequest,
    WaypointStepRequest,
    WaitStepRequest,
    GripperStepRequest,
    LoopStepRequest,
    GroupStepRequest,
    ProgramUpdateRequest,
    DuplicateRequest,
    ImportRequest,
    RepeatRequest,
    SpeedRequest,
    WaypointInfo,
    ProgramInfo,
    ImportFileResponse,
    OtherPrograms,
    ProgramsResponse,
    TeachRecordResponse,
    TeachUndoResponse,
    TeachDraftResponse,
    RepeatProgress,
    TraceResponse,
)

__all__ = [model.__name__ for model in PROGRAM_WIRE_MODELS] + ["PROGRAM_WIRE_MODELS"]
