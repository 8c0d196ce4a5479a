"""Detected blocks."""

from __future__ import annotations

from fastapi import APIRouter

from server.deps import StationDep
from server.models import DetectionsResponse

router = APIRouter(prefix="/api", tags=["detections"])


@router.get("/detections", response_model=DetectionsResponse)
def read_detections(station: StationDep) -> dict:
    """The newest detections (empty until calibrated)."""
    return station.detections().to_dict()
