"""Camera calibration (a job) and pixel → world."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from armlab import skills

from server.deps import ControlAuth, StationDep
from server.models import CalibrationInfo, JobResponse, PixelRequest, PixelToWorldResponse
from server.routes.jobs import job_response

router = APIRouter(prefix="/api", tags=["calibration"])


@router.post("/calibrate", response_model=JobResponse, status_code=202)
def post_calibrate(station: StationDep, controller: ControlAuth, wait: bool = False) -> JSONResponse:
    """Find the board tags, solve the camera pose (cross-checked with depth), save and use it."""
    return job_response(skills.calibrate(station, source=controller), wait)


@router.get("/calibration", response_model=CalibrationInfo)
def read_calibration(station: StationDep) -> dict:
    return station.calibration_info


@router.post("/pixel-to-world", response_model=PixelToWorldResponse)
def post_pixel_to_world(body: PixelRequest, station: StationDep) -> dict:
    """World point under a pixel of the colour image (read-only: no token needed)."""
    return skills.pixel_to_world(station, body.u, body.v)
