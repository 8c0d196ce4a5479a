"""Station state: status, e-stop, reset, and the control lease (take, release, heartbeat)."""

from __future__ import annotations

import asyncio
from functools import partial

from fastapi import APIRouter, Request

from server.deps import ControlAuth, StationDep, StopSource
from server.models import Status

router = APIRouter(prefix="/api", tags=["station"])


async def run_safety(request: Request, function, *args):
    """Run a safety call (e-stop) on the app's own small thread pool, never on the event loop and never
    behind the worker threads that blocked `?wait=true` requests occupy."""
    loop = asyncio.get_running_loop()
    return await loop.run_in_executor(request.app.state.safety_pool, partial(function, *args))


async def run_status(request: Request, function, *args):
    """Run status or reset on the app's status pool: they answer while commands hold every worker thread."""
    loop = asyncio.get_running_loop()
    return await loop.run_in_executor(request.app.state.status_pool, partial(function, *args))


def _reset(station, controller: str) -> dict:
    station.reset(source=controller)
    return station.status()


def _estop(station, controller: str) -> dict:
    station.estop(source=controller)
    return station.status()


@router.get("/status", response_model=Status)
async def read_status(request: Request, station: StationDep) -> dict:
    """State, joints, gripper, gripper pose, controller (lease holder), lost devices, job, allowed commands.
    Served from its own threads and never waiting for the physics (the devices' last control tick)."""
    return await run_status(request, station.status)


@router.post("/estop", response_model=Status)
async def post_estop(request: Request, station: StationDep, controller: StopSource) -> dict:
    """Halt now and latch, in every state, from any client: no token and no control lease needed.

    The latch is set and the arm halted before the station's lock is taken, on a dedicated thread pool:
    neither the event loop nor a blocked request can delay it."""
    return await run_safety(request, _estop, station, controller)


@router.post("/reset", response_model=Status)
async def post_reset(request: Request, station: StationDep, controller: ControlAuth) -> dict:
    """Leave estop/fault for idle without moving the arm (503 while a lost device is still gone)."""
    return await run_status(request, _reset, station, controller)


@router.post("/control/take", response_model=Status)
def post_take_control(station: StationDep, controller: ControlAuth) -> dict:
    """Take the control lease over; every client (the previous controller too) gets an event saying so."""
    station.take_control(controller)
    return station.status()


@router.post("/control/release", response_model=Status)
def post_release_control(station: StationDep, controller: ControlAuth) -> dict:
    """Give the control lease up (nothing happens unless this client holds it)."""
    station.release_control(controller)
    return station.status()


@router.post("/heartbeat", response_model=Status)
def post_heartbeat(station: StationDep, controller: ControlAuth) -> dict:
    """The controller is still there: keeps its hold-to-run jog going for another jog_hold_s."""
    station.heartbeat(source=controller)
    return station.status()
