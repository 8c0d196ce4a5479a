"""Teach mode and taught programs (saved in the station's SQLite file)."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from armlab import skills
from server.deps import ControlAuth, StationDep
from server.models import JobResponse, ProgramId, ProgramInfo, ProgramsResponse, RepeatRequest, Status, TeachStopRequest, WaypointInfo
from server.routes.jobs import job_response

router = APIRouter(prefix="/api", tags=["programs"])


@router.post("/teach/start", response_model=Status)
def post_teach_start(station: StationDep, controller: ControlAuth) -> dict:
    station.teach_start(source=controller)
    return station.status()


@router.post("/teach/record", response_model=WaypointInfo)
def post_teach_record(station: StationDep, controller: ControlAuth) -> dict:
    """Add the current pose and gripper state as a waypoint."""
    return station.teach_record(source=controller).to_dict()


@router.post("/teach/stop", response_model=ProgramInfo)
def post_teach_stop(body: TeachStopRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Save the recorded waypoints as a named program and return to idle."""
    return station.teach_stop(body.name, source=controller).to_dict()


@router.get("/programs", response_model=ProgramsResponse)
def read_programs(station: StationDep) -> dict:
    """Saved programs; a damaged row is left out and named in `skipped`, never hiding the others."""
    programs, skipped = station.store.read_programs()
    return {"data": [program.to_dict() for program in programs], "count": len(programs), "skipped": skipped}


@router.get("/programs/{program_id}", response_model=ProgramInfo)
def read_program(program_id: ProgramId, station: StationDep) -> dict:
    return station.store.get_program(program_id).to_dict()


@router.delete("/programs/{program_id}")
def delete_program(program_id: ProgramId, station: StationDep, controller: ControlAuth) -> dict:
    station.store.delete_program(program_id)
    return {"deleted": program_id}


@router.post("/programs/{program_id}/repeat", response_model=JobResponse, status_code=202)
def post_repeat(
    program_id: ProgramId, station: StationDep, controller: ControlAuth, body: RepeatRequest | None = None, wait: bool = False
) -> JSONResponse:
    """Play a program `cycles` times as a job."""
    cycles = body.cycles if body is not None else 1
    return job_response(skills.repeat(station, program_id, cycles, source=controller), wait)
