"""Autonomous jobs (the auto_sort state): the list of jobs, start one, and (simulation) the judge's score.

Every job comes from armlab.tasks.JOBS, so jobs added there appear here and in the page unchanged.
"""

from __future__ import annotations

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.concurrency import run_in_threadpool

from armlab.tasks import JOBS, JobSpec, start_auto
from armlab.tasks.job_params import param_types
from armlab.tasks.judge import EVENT_LIMITS_S
from armlab.tasks.registry import check_supported, checked_request, unsupported_reason
from server.auto_runs import SCORE_WAIT_S, AutoRun, is_judged, is_scored, watch_run
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import AutoJobsResponse, AutoRequest, AutoResponse, AutoScoreResponse, SceneRequest
from server.waiting import until_job_ended

router = APIRouter(prefix="/api/auto", tags=["auto"])

AUTO_WAIT_TIMEOUT_S = 900.0  # the longest event allows 600 s; a job still running is returned as it stands


def _has_scene(name: str, levels: tuple[int, ...]) -> bool:
    """Whether POST /api/sim/scene generates this job's scenes (whatever that route accepts)."""
    try:
        SceneRequest(event=name, level=levels[0] if levels else 1, seed=0)
    except ValidationError:
        return False
    return True


def _job_info(spec: JobSpec, workcell: str | None = None) -> dict:
    judged = is_judged(spec.name)
    missing = unsupported_reason(spec.name, workcell)
    return {
        "name": spec.name,
        "levels": list(spec.levels),
        "summary": spec.summary,
        "params": [{"name": name, "type": kind} for name, kind in param_types(spec.params_model)],
        "judged": judged,
        "scored": is_scored(spec.name),
        "scene": _has_scene(spec.name, spec.levels),
        "time_limit_s": EVENT_LIMITS_S.get(spec.name) if judged else None,
        "available": missing is None,
        "unavailable_reason": None if missing is None else f"needs {missing}",
    }


def _last_run(request: Request) -> AutoRun | None:
    return getattr(request.app.state, "auto_run", None)


@router.get("/jobs", response_model=AutoJobsResponse)
def read_auto_jobs(station: StationDep) -> dict:
    """The autonomous jobs: levels, summary, parameter names and types, whether the judge scores them, and
    whether the station's workcell can run each (else what it lacks)."""
    data = [_job_info(spec, station.config.workcell) for spec in JOBS.values()]
    return {"data": data, "count": len(data)}


@router.post(
    "", response_model=AutoResponse, status_code=202,
    responses={200: {"model": AutoResponse, "description": "?wait=true: the job once it has ended, with its score"}},
)
async def post_auto(body: AutoRequest, request: Request, station: StationDep, controller: ControlAuth, wait: bool = False) -> JSONResponse:
    """Start an autonomous job in the auto_sort state: 202 {job} at once, or (?wait=true) 200 {job, score}
    once it has ended (the wait holds no worker thread). 422 for an unknown job, level or parameter, or a
    job the station's workcell cannot run (naming what it lacks); 409 unless idle or without a calibration."""

    def start():
        station.allowed_or_raise("auto")
        _, level, params = checked_request(body.job, body.level, body.params)  # params as the job's model read them
        check_supported(body.job, station.config.workcell)
        sim_start_s = station.sim.sim_time_s if station.sim is not None else None
        job = start_auto(station, body.job, level, params, source=controller)
        run = None
        if station.sim is not None:
            run = request.app.state.auto_run = watch_run(job, body.job, level, params, station.sim, sim_start_s, store=station.store,
                                                         workcell=station.config.workcell)
        return job, run

    job, run = await run_in_threadpool(start)
    if not wait:
        return JSONResponse({"job": job.to_dict(), "score": None}, status_code=202)
    await until_job_ended(request, job, AUTO_WAIT_TIMEOUT_S)
    score = await run_in_threadpool(run.to_dict, SCORE_WAIT_S) if run is not None else None
    return JSONResponse({"job": job.to_dict(), "score": score}, status_code=200)


@router.get("/score", response_model=AutoScoreResponse)
def read_auto_score(request: Request, station: StationDep) -> dict:
    """Simulation: the judge's score of the last autonomous job started here (§7 events; the job's own
    scorer for the others), from the ground truth when it ended and the simulated time it took (sim time
    so far and no score while it runs)."""
    if station.sim is None:
        raise ApiError(404, "not_found", "the judge scores runs in the simulation only")
    run = _last_run(request)
    if run is None:
        raise ApiError(404, "not_found", "no autonomous job has been started on this server yet: POST /api/auto")
    return run.to_dict(wait_s=SCORE_WAIT_S)
