"""Station state: status, e-stop, reset."""

from __future__ import annotations

from fastapi import APIRouter

from server.deps import ControlAuth, StationDep
from server.models import Status

router = APIRouter(prefix="/api", tags=["station"])


@router.get("/status", response_model=Status)
def read_status(station: StationDep) -> dict:
    """State, joints, gripper, gripper pose, job and the commands allowed now."""
    return station.status()


@router.post("/estop", response_model=Status)
async def post_estop(station: StationDep, controller: ControlAuth) -> dict:
    """Halt now and latch (allowed in every state).

    Runs on the event loop, not in the worker-thread pool, so an e-stop never waits behind blocked
    `?wait=true` requests; the station's lock is only ever held for short, non-blocking sections.
    """
    station.estop(source=controller)
    return station.status()


@router.post("/reset", response_model=Status)
def post_reset(station: StationDep, controller: ControlAuth) -> dict:
    """Leave estop/fault for idle without moving the arm."""
    station.reset(source=controller)
    return station.status()
