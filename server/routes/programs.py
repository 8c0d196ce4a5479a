"""Teach mode and taught programs (the station's SQLite file): record, undo, save, edit, duplicate, export, import.
Edits (rename, replace, delete, duplicate, import) need the control lease like motion; reading does not.

A recorded waypoint is in the database's teach draft before /api/teach/record answers; a station killed
while teaching resumes the draft on the next /api/teach/start (GET /api/teach/draft shows it).
"""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Body, Query, Response

from armlab.errors import ArmlabError
from armlab.program_formats import ImportOptions
from armlab.skills import program_files
from armlab.skills import programs as program_edits
from armlab.store import MAX_PROGRAM_NAME_CHARS, Waypoint, program_tree
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import ProgramId, Status
from server.program_models import (
    IMPORT_FILE_LIMIT,
    ContinuousRequest,
    ContinuousResponse,
    DuplicateRequest,
    ImportFileResponse,
    ImportRequest,
    ProgramInfo,
    ProgramsResponse,
    ProgramUpdateRequest,
    TeachDraftResponse,
    TeachRecordRequest,
    TeachRecordResponse,
    TeachStartRequest,
    TeachStopRequest,
    TeachUndoResponse,
)

router = APIRouter(prefix="/api", tags=["programs"])


def waypoint_out(station, waypoint) -> dict:
    """A waypoint's wire dict with its gripper point (FK, world frame) for drawing the program's path."""
    if station.model is None:  # no arm: no gripper point to draw
        return {**waypoint.to_dict(), "gripper_position_m": None}
    position = station.model.fk(waypoint.joints_rad)[:3, 3]
    return {**waypoint.to_dict(), "gripper_position_m": [float(v) for v in position]}


def program_out(station, program) -> dict:
    return {**program.to_dict(), "waypoints": [waypoint_out(station, w) for w in program.waypoints]}


@router.post("/teach/start", response_model=Status)
def post_teach_start(station: StationDep, controller: ControlAuth, body: TeachStartRequest | None = None) -> dict:
    """Enter teach; an unsaved draft left by a stopped or killed station is resumed unless discard_draft."""
    station.teach.start(source=controller, discard_draft=bool(body and body.discard_draft))
    return station.status()


@router.post("/teach/record", response_model=TeachRecordResponse)
def post_teach_record(station: StationDep, controller: ControlAuth, body: TeachRecordRequest | None = None) -> dict:
    """Add the current pose and gripper state as a waypoint; on disk (the draft) before this answers."""
    body = body or TeachRecordRequest()
    waypoint, count = station.teach.record(source=controller, dwell_s=body.dwell_s, moving_time_s=body.moving_time_s)
    return {**waypoint_out(station, waypoint), "count": count}


@router.post("/teach/continuous", response_model=ContinuousResponse)
def post_teach_continuous(body: ContinuousRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Trajectory mode: record the pose at rate_hz while it changes (each record on disk, with the time
    since the previous as its moving_time_s), until /api/teach/continuous/stop or teach/stop."""
    station.teach.continuous(body.rate_hz, body.min_change_rad, source=controller)
    return {"recording": True, "rate_hz": body.rate_hz, "recorded": 0, "count": len(station.teach.draft())}


@router.post("/teach/continuous/stop", response_model=ContinuousResponse)
def post_teach_continuous_stop(station: StationDep, controller: ControlAuth) -> dict:
    """End trajectory mode (a no-op when it is not running)."""
    station.allowed_or_raise("teach_record", controller)
    recorded = station.teach.continuous_stop()
    return {"recording": False, "rate_hz": None, "recorded": recorded, "count": len(station.teach.draft())}


@router.post("/teach/undo", response_model=TeachUndoResponse)
def post_teach_undo(station: StationDep, controller: ControlAuth) -> dict:
    """Remove the last recorded waypoint."""
    removed, count = station.teach.undo(source=controller)
    return {"removed": waypoint_out(station, removed) if removed is not None else None, "count": count}


@router.get("/teach/draft", response_model=TeachDraftResponse)
def read_teach_draft(station: StationDep) -> dict:
    """The recorded, not yet saved waypoints (kept across restarts until teach/stop saves them)."""
    waypoints, skipped = station.store.read_draft(station.program_owner)
    return {"waypoints": [waypoint_out(station, w) for w in waypoints], "count": len(waypoints), "skipped": skipped}


@router.post("/teach/stop", response_model=ProgramInfo)
def post_teach_stop(body: TeachStopRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Save the draft as a named program (one transaction) and return to idle."""
    return program_out(station, station.teach.stop(body.name, source=controller))


@router.post("/teach/exit", response_model=Status)
def post_teach_exit(station: StationDep, controller: ControlAuth) -> dict:
    """Leave teach without saving: the draft stays on disk (teach/start resumes it); nothing moves."""
    station.teach.exit(source=controller)
    return station.status()


@router.get("/programs", response_model=ProgramsResponse)
def read_programs(station: StationDep) -> dict:
    """This arm's (and workcell's) saved programs; a damaged row is left out and named in `skipped`, never
    hiding the others; programs of other arms or workcells in the same database are counted in `others`."""
    owned = program_edits.station_programs(station)
    data, skipped = [], list(owned.skipped)
    for program in owned.programs:
        try:
            data.append(program_out(station, program))
        except ArmlabError as error:  # a row this arm cannot draw never hides the others
            skipped.append(f"program {program.id} left out: {error}")
    others = [{"arm": arm, "workcell": workcell, "count": count} for (arm, workcell), count in sorted(owned.others.items(), key=str)]
    return {"data": data, "count": len(data), "skipped": skipped, "others": others, "others_count": sum(owned.others.values())}


@router.get("/programs/{program_id}", response_model=ProgramInfo)
def read_program(program_id: ProgramId, station: StationDep) -> dict:
    """One program of this arm (another arm's: 409 naming its arm)."""
    return program_out(station, program_edits.get_program(station, program_id))


@router.patch("/programs/{program_id}", response_model=ProgramInfo)
def update_program(program_id: ProgramId, body: ProgramUpdateRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Rename and/or replace the whole waypoint list or step tree (every waypoint of the expanded sequence checked
    first; nothing changes if one fails)."""
    station.require_control("edit_program", controller)
    waypoints = None
    if body.waypoints is not None:
        waypoints = [Waypoint(tuple(w.joints_rad), w.gripper, w.dwell_s, w.moving_time_s) for w in body.waypoints]
    if body.steps is not None:
        waypoints = program_tree.steps_from_list([step.model_dump(exclude_none=True) for step in body.steps])
    return program_out(station, program_edits.update_program(station, program_id, name=body.name, waypoints=waypoints))


@router.post("/programs/{program_id}/duplicate", response_model=ProgramInfo, status_code=201)
def post_duplicate(program_id: ProgramId, station: StationDep, controller: ControlAuth, body: DuplicateRequest | None = None) -> dict:
    """Copy a program under a new name (default '<name> (copy)')."""
    station.require_control("duplicate_program", controller)
    return program_out(station, program_edits.duplicate_program(station, program_id, body.name if body else None))


@router.delete("/programs/{program_id}")
def delete_program(program_id: ProgramId, station: StationDep, controller: ControlAuth) -> dict:
    """Delete a program (the lease holder's command, like every edit)."""
    station.require_control("delete_program", controller)
    program_edits.delete_program(station, program_id)
    return {"deleted": program_id}


@router.get(
    "/programs/{program_id}/export",
    response_class=Response,
    responses={200: {"content": {"application/json": {}, "text/csv": {}, "application/octet-stream": {}}, "description": "the program file"}},
)
def export_program(program_id: ProgramId, station: StationDep, format: Literal["json", "csv", "rosbag2"] = "json") -> Response:
    """The program as a file: JSON (everything), CSV `t_s, q1..qn, gripper` (radians; t_s when each waypoint is
    reached) or a ROS 2 bag (one MCAP file: the same timed rows as sensor_msgs/JointState on /<arm>/joint_states)."""
    data, filename, media = program_files.export_program_file(station, program_id, format)
    return Response(data, media_type=media, headers={"Content-Disposition": f'attachment; filename="{filename}"'})


@router.post("/programs/import", response_model=ProgramInfo, status_code=201)
def post_import(body: ImportRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Store a program from an exported file's text; a malformed file is refused (422 naming the line and
    the reason) and nothing stored changes."""
    station.require_control("import_program", controller)
    return program_out(station, program_edits.import_program(station, body.format, body.content, body.name))


@router.post("/programs/import/file", response_model=ImportFileResponse, status_code=201)
def post_import_file(
    station: StationDep,
    controller: ControlAuth,
    content: Annotated[bytes, Body(media_type="application/octet-stream", description="the file's bytes")],
    format: Literal["rosbag2", "jointdata", "csv", "json"],
    name: Annotated[str | None, Query(min_length=1, max_length=MAX_PROGRAM_NAME_CHARS, description="default: the file's own or 'imported <format>'")] = None,
    mode: Literal["waypoints", "trajectory"] = "waypoints",
    clamp_rad: Annotated[float, Query(ge=0.0, le=1.0, description="clamp samples beyond a joint limit by at most this (0: refuse them)")] = 0.0,
    topic: Annotated[str | None, Query(min_length=1, max_length=256, description="rosbag2: the JointState topic")] = None,
) -> dict:
    """Store an uploaded file as a new program: a ROS 2 bag (one .mcap or .db3 file, or a .zip of the bag folder)
    of joint states, the course's joint text (jointdata), or the station's CSV or JSON. Refused (422 saying why:
    no joint states, other joint names, beyond the limits without clamp_rad, a damaged file) with nothing stored."""
    station.require_control("import_program", controller)
    if len(content) > IMPORT_FILE_LIMIT:
        raise ApiError(413, "invalid", f"the file has {len(content)} bytes; at most {IMPORT_FILE_LIMIT}")
    imported = program_files.import_program_file(station, format, data=content, name=name, topic=topic,
                                                 options=ImportOptions(mode=mode, clamp_rad=clamp_rad))
    return {**program_out(station, imported.program), "notes": imported.notes, "clamped_rad": imported.clamped_rad,
            "clamped_samples": imported.clamped_samples, "samples": imported.samples}
