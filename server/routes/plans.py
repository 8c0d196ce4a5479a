"""Plan, then execute (issue 22 item 2): execute or discard a plan a `?plan_only=true` move made. Execute sends exactly
the plan's trajectory through the station's gate, or refuses with nothing moved: unknown id 404, executed already or
stale 409 `stale_plan` (with its reason), another controller's plan 409 `not_controller`, no token 401."""

from __future__ import annotations

from fastapi import APIRouter, Path, Request
from starlette.concurrency import run_in_threadpool

from armlab.station.job_control import SPEED_WAIT_FACTOR, StepTaken
from armlab.station.jobs import Job
from server.deps import ControlAuth, StationDep
from server.models import Status
from server.plan_models import PlanDiscarded
from server.routes.jobs import JOB_WAIT_TIMEOUT_S
from server.waiting import until_arm_still, until_job_ended, until_step_taken

router = APIRouter(prefix="/api", tags=["arm"])

PlanId = Path(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.:-]+$", description="the id a plan_only move answered")


@router.post("/plans/{plan_id}/execute", response_model=Status)
async def post_execute_plan(request: Request, station: StationDep, controller: ControlAuth, plan_id: str = PlanId,
                            wait: bool = False) -> dict:
    """Send exactly the plan's trajectory (the gate's checks as any motion: state, lease, latch, the start at the
    measured joints), or for a grab's or drop's plan start its job with exactly its steps, for a paused job's next
    step hand the job exactly that step; ?wait=true answers once the arm has stopped (the job has ended, the job
    waits at its next step again)."""
    sent = await run_in_threadpool(station.execute_plan, plan_id, controller)
    if wait and isinstance(sent, StepTaken):  # a paused job's next step: until it waits at the one after (or ended)
        await until_step_taken(request, sent, JOB_WAIT_TIMEOUT_S)
    elif wait and isinstance(sent, Job):
        await until_job_ended(request, sent, JOB_WAIT_TIMEOUT_S)
    elif wait:
        await until_arm_still(request, station, sent.duration_s * SPEED_WAIT_FACTOR + 5.0)
    return await run_in_threadpool(station.status)


@router.delete("/plans/{plan_id}", response_model=PlanDiscarded)
def delete_plan(station: StationDep, controller: ControlAuth, plan_id: str = PlanId) -> dict:
    """Discard a plan (Cancel): executing it is then refused (404)."""
    station.discard_plan(plan_id, controller)
    return {"plan_id": plan_id, "discarded": True}
