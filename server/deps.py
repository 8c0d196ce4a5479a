"""FastAPI dependencies: the station (StationDep), the control-token check (ControlAuth) and the name of
whoever stops the arm (StopSource: no token needed, stopping is always allowed).

Both are `async def` so they run on the event loop (they do no I/O): an e-stop route never waits for a
free worker thread just to resolve its dependencies.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Header, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from armlab.station.core import Station
from armlab.station.lease import checked_controller
from server.auth import token_matches
from server.errors import ApiError

# The control token as an OpenAPI security scheme ('Authorization: Bearer <token>', scheme name case-insensitive).
control_token = HTTPBearer(auto_error=False, scheme_name="ControlToken", description="the control token printed at start-up")


async def get_station(request: Request) -> Station:
    station = getattr(request.app.state, "station", None)
    if station is None:
        raise ApiError(503, "device", "the station is not running")
    return station


async def require_control(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(control_token)],
    x_armlab_controller: Annotated[
        str | None, Header(description="this client's controller name for the control lease (1-64 of A-Z a-z 0-9 _ . : -)")
    ] = None,
) -> str:
    """Check 'Authorization: Bearer <token>' (the scheme name in any case, as RFC 7235 says); returns the
    controller's name for the lease: the X-Armlab-Controller header, else 'ui' for a browser page
    (browsers add Sec-Fetch-Mode to fetch() calls) and 'api' for a script."""
    given = credentials.credentials.strip() if credentials is not None else None
    if not token_matches(request.app.state.token, given or None):
        raise ApiError(401, "unauthorized", "this command needs the control token: send 'Authorization: Bearer <token>'")
    return _client_name(request, x_armlab_controller)


def _client_name(request: Request, x_armlab_controller: str | None) -> str:
    """The X-Armlab-Controller name (validated), else 'ui' for a browser page and 'api' for a script."""
    declared = (x_armlab_controller or "").strip()
    if declared:
        try:
            return checked_controller(declared)
        except ValueError as error:
            raise ApiError(422, "invalid", f"X-Armlab-Controller: {error}") from error
    return "ui" if "sec-fetch-mode" in request.headers else "api"


async def stop_source(
    request: Request,
    x_armlab_controller: Annotated[str | None, Header(description="the caller's name, for the event log")] = None,
) -> str:
    """Who asks for the stop. No token: any page the station serves may stop the arm (the Host/Origin
    guard still keeps other sites out), and stopping never needs the control lease."""
    return _client_name(request, x_armlab_controller)


StationDep = Annotated[Station, Depends(get_station)]
ControlAuth = Annotated[str, Depends(require_control)]
StopSource = Annotated[str, Depends(stop_source)]
