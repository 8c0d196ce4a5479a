"""The station's global speed override (10-100 %): every motion it plans, jobs, manual moves and repeats, runs at it;
a change re-times the motion in progress continuously (armlab/station/job_control.py set_speed, motion.py). PATCH /api/jobs/current sets the
same override for a running repeat."""

from __future__ import annotations

from fastapi import APIRouter
from starlette.concurrency import run_in_threadpool

from server.deps import ControlAuth, StationDep
from server.program_models import SpeedRequest, SpeedResponse

router = APIRouter(prefix="/api", tags=["station"])


@router.get("/speed", response_model=SpeedResponse)
def read_speed(station: StationDep) -> dict:
    """The speed override in force (% of full speed)."""
    return {"speed_percent": station.speed_percent}


@router.put("/speed", response_model=SpeedResponse)
async def put_speed(body: SpeedRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Set the speed override (10-100 %; NaN, text, out of range: 422 and nothing changes). A running repeat re-plans
    the rest of its run at it; any other motion in progress is re-timed along its path from now on."""
    speed = await run_in_threadpool(station.set_speed, body.speed_percent, controller)
    return {"speed_percent": speed}
