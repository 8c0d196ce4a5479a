"""Repeat a taught program, and the running repeat's controls: pause, resume, step, speed, joint trace."""

from __future__ import annotations

import csv
import io
from typing import Literal

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from armlab import skills
from armlab.skills import program_files
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import JobResponse, ProgramId
from server.plan_models import MovePlan
from server.program_models import RepeatRequest, SpeedRequest, TraceResponse
from server.routes.jobs import PLAN_ONLY, WAITED_JOB_OR_PLAN, job_response

router = APIRouter(prefix="/api", tags=["repeat"])


@router.post("/programs/{program_id}/repeat", response_model=JobResponse, status_code=202, responses=WAITED_JOB_OR_PLAN)
async def post_repeat(
    request: Request, program_id: ProgramId, station: StationDep, controller: ControlAuth, body: RepeatRequest | None = None,
    wait: bool = False, plan_only: bool = PLAN_ONLY,
) -> JSONResponse:
    """Repeat a program `cycles` times (None: until cancelled) at `speed_percent`, as a job: every waypoint
    and segment checked first, eased in from the current pose, paced by absolute deadlines, home at the end.
    ?plan_only=true: the plan (the ease-in, one cycle, the way home), nothing moves; Execute starts the repeat on it."""
    body = body or RepeatRequest()
    started = await run_in_threadpool(lambda: skills.repeat(station, program_id, body.cycles, body.speed_percent,
                                                            source=controller, plan_only=plan_only))
    if plan_only:
        return JSONResponse(started, status_code=200)
    return await job_response(request, started, wait)


def _job(job) -> dict:
    return {"job": job.to_dict() if job is not None else None}


@router.post("/jobs/pause", response_model=JobResponse)
def post_pause(station: StationDep, controller: ControlAuth) -> dict:
    """Pause the running repeat: the arm brakes to rest (jerk-limited) and holds."""
    return _job(station.pause_job(source=controller))


@router.post("/jobs/resume", response_model=JobResponse)
def post_resume(station: StationDep, controller: ControlAuth) -> dict:
    """Resume a paused repeat from where the arm stopped."""
    return _job(station.resume_job(source=controller))


STEP_PLAN = {200: {"model": JobResponse | MovePlan, "description": "the job; ?plan_only=true: the next step's plan (MovePlan), "
                   "nothing moves"}}


@router.post("/jobs/step", response_model=JobResponse, responses=STEP_PLAN)
def post_step(station: StationDep, controller: ControlAuth, plan_only: bool = Query(
        False, description="the paused job's next step (the next waypoint's move, or the gripper step it waits at) "
        "planned as the step would run, nothing moves: answers the plan (MovePlan) with its id for POST "
        "/api/plans/{plan_id}/execute, which hands the job exactly that step")) -> dict | JSONResponse:
    """Paused: go on to the next waypoint (and do what it says), then pause again; running: pause.
    ?plan_only=true (the job paused at rest): the next step's plan."""
    if plan_only:
        return JSONResponse(station.plan_job_step(source=controller), status_code=200)
    return _job(station.step_job(source=controller))


@router.patch("/jobs/current", response_model=JobResponse)
def patch_current_job(body: SpeedRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Change the running repeat's speed override (10-100 %); the motion in progress is re-planned smoothly."""
    return _job(station.set_job_speed(body.speed_percent, source=controller))


@router.get(
    "/jobs/current/trace",
    response_model=TraceResponse,
    responses={200: {"content": {"application/json": {}, "text/csv": {}, "application/octet-stream": {}}, "description": "the trace"}},
)
def read_trace(station: StationDep, format: Literal["json", "csv", "rosbag2"] = "json"):
    """Commanded and measured joint angles (rad) over the last complete cycle of the current or last repeat (rosbag2:
    one MCAP file, measured on /<arm>/joint_states and commanded on /<arm>/commanded/joint_states)."""
    job = station.current_job()
    trace = getattr(getattr(job, "control", None), "trace", None)
    if trace is None:
        raise ApiError(404, "not_found", "no repeat has run yet: the trace is of the current or last repeat job")
    snapshot = trace.snapshot()
    names = snapshot["joint_names"]
    columns = ["t_s", *(f"{n}_cmd_rad" for n in names), *(f"{n}_meas_rad" for n in names)]
    if format == "rosbag2":
        data = program_files.trace_bag(station, snapshot["samples"], names)
        filename = f"repeat-{job.id}-cycle-{snapshot['cycle']}.mcap"
        return Response(data, media_type="application/octet-stream", headers={"Content-Disposition": f'attachment; filename="{filename}"'})
    if format == "csv":
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(columns)
        writer.writerows(snapshot["samples"])
        filename = f"repeat-{job.id}-cycle-{snapshot['cycle']}.csv"
        return Response(out.getvalue(), media_type="text/csv", headers={"Content-Disposition": f'attachment; filename="{filename}"'})
    return {"job_id": job.id, "columns": columns, **snapshot}
