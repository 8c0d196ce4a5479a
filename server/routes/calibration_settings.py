"""The operator's calibration settings: self-recalibration when idle once the camera moved."""

from __future__ import annotations

from fastapi import APIRouter
from pydantic import BaseModel, Field

from server.deps import ControlAuth, StationDep
from server.models import Request

router = APIRouter(prefix="/api/calibration", tags=["calibration"])


class CalibrationSettingsRequest(Request):
    self_recalibrate: bool = Field(description="recalibrate from the board tags when idle once the camera moved")


class CalibrationSettings(BaseModel):
    self_recalibrate: bool
    calibration_state: str | None = Field(None, description="trusted | checking | rejected | None (no calibration)")


def _settings(station) -> dict:
    return {"self_recalibrate": station.trust.self_recalibrate, "calibration_state": station.trust.state}


@router.get("/settings", response_model=CalibrationSettings)
def read_calibration_settings(station: StationDep) -> dict:
    return _settings(station)


@router.put("/settings", response_model=CalibrationSettings)
def put_calibration_settings(body: CalibrationSettingsRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Turn self-recalibration on or off (the control lease holder only). On: when the camera-moved
    warning is up and the station is idle (no job, arm still, not e-stopped) with enough board tags in
    view, it recalibrates from the tags, logs it and clears the warning. Off: the warning stays."""
    station.trust.set_self_recalibrate(body.self_recalibrate, source=controller)
    return _settings(station)
