"""Camera calibration (a job) and pixel → world."""

from __future__ import annotations

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from armlab import skills
from server.deps import ControlAuth, StationDep
from server.models import CalibrationInfo, JobResponse, PixelRequest, PixelToWorldResponse, PointsCalibrationRequest
from server.routes.jobs import WAITED_JOB, job_response

router = APIRouter(prefix="/api", tags=["calibration"])


@router.post("/calibrate", response_model=JobResponse, status_code=202, responses=WAITED_JOB)
async def post_calibrate(request: Request, station: StationDep, controller: ControlAuth, wait: bool = False) -> JSONResponse:
    """Find the board tags, solve the camera pose (cross-checked with depth), save and use it."""
    return await job_response(request, await run_in_threadpool(skills.calibrate, station, source=controller), wait)


@router.post("/calibrate/points", response_model=JobResponse, status_code=202, responses=WAITED_JOB)
async def post_calibrate_points(
    request: Request, body: PointsCalibrationRequest, station: StationDep, controller: ControlAuth, wait: bool = False
) -> JSONResponse:
    """Calibrate from >= 4 clicked pixels with known world points (no tags needed): homography + PnP,
    reprojection error per point; too few, collinear or inconsistent points fail the job saying why."""
    pixels = [p.pixel for p in body.points]
    world = [p.world_m for p in body.points]
    job = await run_in_threadpool(skills.calibrate_points, station, pixels, world, source=controller)
    return await job_response(request, job, wait)


@router.post("/calibrate/arm-camera", response_model=JobResponse, status_code=202, responses=WAITED_JOB)
async def post_calibrate_arm_camera(
    request: Request, station: StationDep, controller: ControlAuth, wait: bool = False, use: bool = False
) -> JSONResponse:
    """Calibrate the camera from the arm, without tags: checked poses over the board, the gripper's tag found in
    each, Kabsch; each pose's residual and the disagreement with the calibration in use in the result. That
    calibration stays unless use=true; too few usable poses or a bad fit fail the job saying why."""
    job = await run_in_threadpool(skills.calibrate_arm_camera, station, use=use, source=controller)
    return await job_response(request, job, wait)


@router.post("/calibrate/arm", response_model=JobResponse, status_code=202, responses=WAITED_JOB)
async def post_calibrate_arm(request: Request, station: StationDep, controller: ControlAuth, wait: bool = False) -> JSONResponse:
    """Calibrate the arm from the camera: checked poses over the board, the gripper's tag seen by the calibrated
    camera in each, the fit (joint offsets, compliance, base pose; residual before and after in the result),
    installed for every motion and saved. Refused (the job fails saying why, the arm calibration in use kept)
    with the camera uncalibrated, a block held, the tag seen at too few poses, or a fit no better than nominal."""
    return await job_response(request, await run_in_threadpool(skills.calibrate_arm, station, source=controller), wait)


@router.get("/calibration", response_model=CalibrationInfo)
def read_calibration(station: StationDep) -> dict:
    return station.calibration_info


@router.post("/pixel-to-world", response_model=PixelToWorldResponse)
def post_pixel_to_world(body: PixelRequest, station: StationDep) -> dict:
    """World point under a pixel of the colour image, and the raw depth reading there (read-only: no token needed)."""
    result = skills.pixel_to_world(station, body.u, body.v)
    return {**result, "depth_mm": raw_depth_mm(station, body.u, body.v)}


def raw_depth_mm(station, u: float, v: float) -> float | None:
    """The newest frame's depth reading at pixel (u, v) in mm (0: no reading), None without a depth image."""
    frame, _ = station.frames.get()
    depth = getattr(frame, "depth_mm", None)
    if depth is None:
        return None
    row, col = int(round(v)), int(round(u))
    if not (0 <= row < depth.shape[0] and 0 <= col < depth.shape[1]):
        return None
    return float(depth[row, col])
