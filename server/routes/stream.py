"""The websocket stream (/ws) and single JPEG snapshots (/api/frame.jpg)."""

from __future__ import annotations

from fastapi import APIRouter, Query, WebSocket
from fastapi.responses import Response

from server.auth import token_matches
from server.deps import StationDep
from server.errors import ApiError
from server.views import ViewKey, compose_view, encode_jpeg

router = APIRouter(tags=["stream"])


@router.get("/api/frame.jpg", response_class=Response, responses={200: {"content": {"image/jpeg": {}}}})
def read_frame(
    station: StationDep,
    layers: str | None = Query(None, description="comma-separated: tags,detections,grid"),
    view: str = Query("color", description="color | depth | topdown"),
) -> Response:
    """The newest frame as JPEG with the requested overlays; X-Capture-Time-S holds its capture time."""
    try:
        key = ViewKey.parse(view, layers)
    except ValueError as error:
        raise ApiError(422, "invalid", str(error)) from error
    frame = station.fresh_frame()
    perception, _ = station.perception.get()
    image = compose_view(frame, key, perception, station.calibration, station.perception_config)
    return Response(
        encode_jpeg(image, station.config.jpeg_quality),
        media_type="image/jpeg",
        headers={"X-Capture-Time-S": f"{frame.timestamp_s:.6f}", "X-Frame-Seq": str(frame.sequence), "Cache-Control": "no-store"},
    )


@router.websocket("/ws")
async def websocket_stream(websocket: WebSocket, token: str | None = None, controller: str | None = None) -> None:
    """Frames (binary, after ack), telemetry, events, calibration; control messages need ?token=.
    ?controller=NAME names this session for the control lease (default: a name of its own)."""
    app = websocket.app
    await websocket.accept()
    if token is not None and not token_matches(app.state.token, token):  # accepted first so the page sees the code
        await websocket.close(code=4401, reason="wrong control token")
        return
    try:
        name = app.state.hub.session_controller(controller)
    except ValueError as error:
        await websocket.close(code=4422, reason=str(error)[:120])
        return
    await app.state.hub.serve(websocket, can_control=token is not None, controller=name)
