"""Recordings: MCAP files of the station's channels (armlab.recording). Start and stop (one at a time), list,
download, delete. Starting, stopping and deleting need the control token and the lease, like program edits;
listing and downloading do not."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Request
from fastapi.responses import FileResponse

from armlab.recording import RecordingBusy, RecordingLibrary
from armlab.recording.recorder import MB
from server.deps import ControlAuth, StationDep
from server.errors import ApiError
from server.models import ErrorResponse
from server.recording_models import RecordingResponse, RecordingsResponse, RecordingStartRequest

router = APIRouter(prefix="/api", tags=["recordings"])

RecordingId = Annotated[str, Path(max_length=64, description="a recording id, e.g. 20261203T100000Z-a1b2c3")]
DISK_FULL = {507: {"model": ErrorResponse, "description": "too little free disk to start a recording (recording.min_free_mb)"}}


def library(request: Request) -> RecordingLibrary:
    recordings = getattr(request.app.state, "recordings", None)
    if recordings is None:
        raise ApiError(503, "device", "the station is not running")
    return recordings


@router.post("/recordings/start", response_model=RecordingResponse, status_code=201, responses=DISK_FULL)
def post_recording_start(request: Request, station: StationDep, controller: ControlAuth, body: RecordingStartRequest | None = None) -> dict:
    """Start recording the station to MCAP; 409 while a recording runs (it goes on untouched)."""
    station.require_control("record", controller)
    return {"recording": library(request).start(station, label=body.label if body else "", source=controller)}


@router.post("/recordings/stop", response_model=RecordingResponse)
def post_recording_stop(request: Request, station: StationDep, controller: ControlAuth) -> dict:
    """Stop the running recording (its file closed, complete); 409 when nothing is recording."""
    station.require_control("record", controller)
    return {"recording": library(request).stop()}


@router.get("/recordings", response_model=RecordingsResponse)
def read_recordings(request: Request) -> dict:
    """Every recording, newest first, with duration, size and messages per topic; the running one as `active`."""
    recordings = library(request)
    data = recordings.list()
    return {"data": data, "count": len(data), "active": recordings.active(), "directory": str(recordings.directory),
            "total_bytes": sum(item["size_bytes"] for item in data), "budget_bytes": int(recordings.config.budget_mb * MB)}


@router.get("/recordings/{recording_id}", response_class=FileResponse,
            responses={200: {"content": {"application/octet-stream": {}}, "description": "the MCAP file"}})
def read_recording(request: Request, recording_id: RecordingId) -> FileResponse:
    """Download a recording (.mcap; open it in Foxglove); 409 while it is still being written."""
    recordings = library(request)
    path = recordings.path(recording_id)
    if recordings.active() is not None and recordings.active()["id"] == recording_id:
        raise RecordingBusy(f"recording {recording_id} is still being written: stop it first")
    return FileResponse(path, media_type="application/octet-stream", filename=f"{recording_id}.mcap")


@router.delete("/recordings/{recording_id}")
def delete_recording(request: Request, recording_id: RecordingId, station: StationDep, controller: ControlAuth) -> dict:
    """Delete a recording (not the running one: 409)."""
    station.require_control("delete_recording", controller)
    library(request).delete(recording_id)
    return {"deleted": recording_id}



