"""Camera intrinsics: what is in use (measured here, else the camera's own) and the guided checkerboard
capture that measures them (armlab/station/intrinsics.py). Refusals (board not found, blurry, duplicate,
too few views, error too high) are 422 with the reason; the intrinsics in use stay as they were."""

from __future__ import annotations

import time
from typing import Annotated

from fastapi import APIRouter, Path

from armlab import skills
from armlab.vision.intrinsics_capture import IntrinsicsRejected
from server.deps import ControlAuth, StationDep
from server.errors import ApiError

router = APIRouter(prefix="/api/intrinsics", tags=["calibration"])
FRAME_WAIT_S = 3.0


def _checked(station, controller: str):
    """The station's intrinsics keeper, once the state (idle) and the control lease allow calibrating."""
    station.allowed_or_raise("calibrate", controller)
    return station.intrinsics


def _refused(error: IntrinsicsRejected) -> ApiError:
    return ApiError(422, "invalid", str(error))


@router.get("")
def read_intrinsics(station: StationDep) -> dict:
    """The intrinsics in use (source: measured or factory), the camera's own, whether the camera
    calibration was solved with other intrinsics, and the capture session if one runs."""
    return station.intrinsics.info(station.calibration)


@router.post("/session")
def post_session(station: StationDep, controller: ControlAuth) -> dict:
    """Start (or restart) a capture: no views yet."""
    return _checked(station, controller).start_session()


@router.delete("/session")
def delete_session(station: StationDep, controller: ControlAuth) -> dict:
    """Cancel the capture; the intrinsics in use are unchanged."""
    _checked(station, controller).cancel()
    return {"cancelled": True}


@router.post("/capture")
def post_capture(station: StationDep, controller: ControlAuth) -> dict:
    """Check the newest frame (taken after this request arrived) and keep it as a view, or say why not."""
    keeper = _checked(station, controller)
    frame = station.frame_after(time.time(), FRAME_WAIT_S)
    try:
        return keeper.capture(frame.color_bgr)
    except IntrinsicsRejected as error:
        raise _refused(error) from error


@router.delete("/views/{index}")
def delete_view(index: Annotated[int, Path(ge=0, le=1000)], station: StationDep, controller: ControlAuth) -> dict:
    """Drop one kept view (e.g. the one with the worst error)."""
    try:
        return _checked(station, controller).delete_view(index)
    except IntrinsicsRejected as error:
        raise _refused(error) from error


@router.post("/solve")
def post_solve(station: StationDep, controller: ControlAuth) -> dict:
    """K, distortion, RMS and per-view errors from the kept views; waits for accept."""
    try:
        return _checked(station, controller).solve()
    except IntrinsicsRejected as error:
        raise _refused(error) from error


@router.post("/accept")
def post_accept(station: StationDep, controller: ControlAuth, recalibrate: bool = False) -> dict:
    """Store the solved intrinsics for this camera and use them. The camera calibration is kept (it stays
    self-consistent) but reported outdated; recalibrate=true starts the tag calibration job with the new
    intrinsics at once (if it fails, e.g. no tags in view, the old calibration is kept)."""
    keeper = _checked(station, controller)
    try:
        result = keeper.accept()
    except IntrinsicsRejected as error:
        raise _refused(error) from error
    info = keeper.info(station.calibration)
    body = {"accepted": result, "calibration_outdated": info["calibration_outdated"], "note": info["note"]}
    if recalibrate and station.calibration is not None:
        body["job"] = skills.calibrate(station, source=controller).to_dict()
    return body
