"""Recordings: MCAP files of the station's channels (armlab.recording). Start and stop (one at a time), list,
download, export (a LeRobot dataset as a zip), delete. Starting, stopping and deleting need the control token and the
lease, like program edits; listing, downloading and exporting do not."""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from pathlib import Path as FilePath
from typing import Annotated, Literal

from fastapi import APIRouter, Path, Query, Request
from fastapi.responses import FileResponse
from starlette.background import BackgroundTask

from armlab.recording import RecordingBusy, RecordingLibrary
from armlab.recording.lerobot import export_library_recordings
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


@router.get("/recordings/{recording_id}/export", response_class=FileResponse,
            responses={200: {"content": {"application/zip": {}}, "description": "the dataset's folder as a zip"}})
def read_recording_export(
    request: Request, recording_id: RecordingId, format: Literal["lerobot"] = "lerobot",
    fps: Annotated[int, Query(ge=1, le=240, description="frames per second of the dataset")] = 30,
    task: Annotated[str | None, Query(max_length=200, description="the episode's task (default: the label, else its jobs)")] = None,
    allow_truncated: Annotated[bool, Query(description="export a recording cut short up to its last complete chunk")] = False,
) -> FileResponse:
    """A recording as a LeRobot v3.0 dataset (one episode: observation.state, action, the camera as AV1 video), zipped:
    <id>-lerobot/meta/info.json, ...; 409 while it is being written, 422 when it cannot be exported (empty, no camera,
    cut short without allow_truncated)."""
    work = FilePath(tempfile.mkdtemp(prefix="armlab-lerobot-"))
    try:
        name = f"{recording_id}-lerobot"
        export_library_recordings(library(request), [recording_id], work / name, fps=fps, tasks=[task], allow_truncated=allow_truncated)
        archive = work / f"{name}.zip"
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_STORED) as zipped:  # parquet and AV1 are compressed already
            for file in sorted((work / name).rglob("*")):
                if file.is_file():
                    zipped.write(file, file.relative_to(work).as_posix())
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    return FileResponse(archive, media_type="application/zip", filename=archive.name,
                        background=BackgroundTask(shutil.rmtree, work, ignore_errors=True))


@router.delete("/recordings/{recording_id}")
def delete_recording(request: Request, recording_id: RecordingId, station: StationDep, controller: ControlAuth) -> dict:
    """Delete a recording (not the running one: 409)."""
    station.require_control("delete_recording", controller)
    library(request).delete(recording_id)
    return {"deleted": recording_id}



