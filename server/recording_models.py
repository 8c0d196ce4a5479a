"""Wire models of the recording routes (server/routes/recordings.py)."""

from __future__ import annotations

from pydantic import Field

from server.wire_base import Request, Wire


class RecordingStartRequest(Request):
    """Start recording the station to MCAP (one recording at a time)."""

    label: str = Field("", max_length=200, description="what is recorded, for the list (e.g. 'teach: stack of three')")


class RecordingInfo(Wire):
    """One recording: an MCAP file in Foxglove's schemas (joint states, gripper, transforms, camera, detections, events)."""

    id: str = Field(description="e.g. 20261203T100000Z-a1b2c3 (its UTC start time)")
    label: str = ""
    source: str | None = Field(None, description="who started it (the controller's name)")
    started_utc: str
    state: str = Field(description="recording, finished or damaged")
    stop_reason: str | None = Field(None, description="why it ended: stopped, disk full, budget reached, cut short, ...")
    duration_s: float
    size_bytes: int
    complete: bool = Field(description="the file was closed with MCAP's summary")
    truncated: bool = Field(description="cut short (the station was killed): readable up to its last complete chunk")
    topics: dict[str, int] = Field(description="messages per topic")
    jobs: list[str] = Field(description="the jobs that ran while it recorded")
    states: list[str] = Field([], description="the station's states while it recorded (idle, teach, repeat, auto_sort, ...), in order")
    sampler_error: str | None = None


class RecordingResponse(Wire):
    recording: RecordingInfo


class RecordingsResponse(Wire):
    data: list[RecordingInfo]
    count: int
    active: RecordingInfo | None = Field(description="the recording running now, if any")
    directory: str
    total_bytes: int
    budget_bytes: int


RECORDING_WIRE_MODELS = (RecordingStartRequest, RecordingInfo, RecordingResponse, RecordingsResponse)
