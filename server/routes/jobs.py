"""Jobs: click-grab and click-drop (202 + job, or 200 + the ended job with ?wait=true: the wait holds no
worker thread, server/waiting.py), current job, cancel."""

from __future__ import annotations

from fastapi import APIRouter, Query, Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from armlab import skills
from armlab.station.jobs import Job
from server.deps import ControlAuth, StationDep
from server.models import JobResponse, TargetCheckResponse, TargetRequest
from server.plan_models import MovePlan
from server.waiting import until_job_ended

router = APIRouter(prefix="/api", tags=["jobs"])

JOB_WAIT_TIMEOUT_S = 300.0


# What a job-starting route documents: 202 at once, or 200 with ?wait=true once the job has ended.
WAITED_JOB = {200: {"model": JobResponse, "description": "?wait=true: the job once it has ended (or as it stands after the wait's timeout)"}}
# grab and drop also plan without moving: 200 with the plan.
WAITED_JOB_OR_PLAN = {200: {"model": JobResponse | MovePlan, "description": "?wait=true: the job once it has ended (or as it "
                            "stands after the wait's timeout); ?plan_only=true: the plan (MovePlan), nothing moves"}}
PLAN_ONLY = Query(False, description="plan the job's motions and check them as it would, move nothing: answers the plan "
                  "(MovePlan) with its id for POST /api/plans/{plan_id}/execute, which runs exactly those steps")


async def job_response(request: Request, job: Job, wait: bool) -> JSONResponse:
    """202 {job} at once, or (wait) 200 {job} once it has ended."""
    if wait:
        await until_job_ended(request, job, JOB_WAIT_TIMEOUT_S)
        return JSONResponse({"job": job.to_dict()}, status_code=200)
    return JSONResponse({"job": job.to_dict()}, status_code=202)


def _target(body: TargetRequest) -> dict:
    if body.position_m is not None:
        return {"position_m": body.position_m}
    return {"pixel": (body.u, body.v)}


async def _job_or_plan(request: Request, started, wait: bool) -> JSONResponse:
    """A job started (job_response), or a plan kept (200 with the plan)."""
    if isinstance(started, Job):
        return await job_response(request, started, wait)
    return JSONResponse(started, status_code=200)


@router.post("/grab", response_model=JobResponse, status_code=202, responses=WAITED_JOB_OR_PLAN)
async def post_grab(request: Request, body: TargetRequest, station: StationDep, controller: ControlAuth, wait: bool = False,
                    plan_only: bool = PLAN_ONLY) -> JSONResponse:
    """Grab the detected block under the target (centre, top, yaw), else at the target point."""
    started = await run_in_threadpool(lambda: skills.grab(station, **_target(body), source=controller, plan_only=plan_only))
    return await _job_or_plan(request, started, wait)


@router.post("/drop", response_model=JobResponse, status_code=202, responses=WAITED_JOB_OR_PLAN)
async def post_drop(request: Request, body: TargetRequest, station: StationDep, controller: ControlAuth, wait: bool = False,
                    plan_only: bool = PLAN_ONLY) -> JSONResponse:
    """Place the held block at the target, on the board or on top of the block/stack there."""
    started = await run_in_threadpool(lambda: skills.drop(station, **_target(body), source=controller, plan_only=plan_only))
    return await _job_or_plan(request, started, wait)


@router.post("/grab/check", response_model=TargetCheckResponse)
def post_grab_check(body: TargetRequest, station: StationDep) -> dict:
    """What a grab at the target would do, planned as the grab plans it, nothing moved (read-only: the page's reach
    state while the pointer rests in Click-grab mode). A refusal is the grab's own error, saying what to do."""
    return {"ok": True, "detail": skills.grab(station, **_target(body), check_only=True)}


@router.post("/drop/check", response_model=TargetCheckResponse)
def post_drop_check(body: TargetRequest, station: StationDep) -> dict:
    """As /api/grab/check, for a drop."""
    return {"ok": True, "detail": skills.drop(station, **_target(body), check_only=True)}


@router.get("/jobs/current", response_model=JobResponse)
def read_current_job(station: StationDep) -> dict:
    """The running job, else the last finished one, else null."""
    job = station.current_job()
    return {"job": job.to_dict() if job is not None else None}


@router.get("/jobs/history")
def read_job_history(station: StationDep, limit: int = 20) -> dict:
    """Recent job outcomes from the database."""
    data = station.store.job_results(max(1, min(limit, 200)))
    return {"data": data, "count": len(data)}


@router.post("/jobs/cancel", response_model=JobResponse)
def post_cancel(station: StationDep, controller: ControlAuth) -> dict:
    job = station.cancel_job(source=controller)
    return {"job": job.to_dict()}
