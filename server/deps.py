"""FastAPI dependencies: the station (StationDep) and the control-token check (ControlAuth)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Header, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from armlab.station.core import Station
from server.auth import token_matches
from server.errors import ApiError

# The control token as an OpenAPI security scheme ('Authorization: Bearer <token>', scheme name case-insensitive).
control_token = HTTPBearer(auto_error=False, scheme_name="ControlToken", description="the control token printed at start-up")


def get_station(request: Request) -> Station:
    station = getattr(request.app.state, "station", None)
    if station is None:
        raise ApiError(503, "device", "the station is not running")
    return station


def require_control(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(control_token)],
    x_armlab_controller: Annotated[str | None, Header()] = None,
) -> str:
    """Check 'Authorization: Bearer <token>'; returns who controls: 'ui' or 'api'.

    'ui' when the request says so (X-Armlab-Controller: ui) or comes from a browser page (browsers
    add Sec-Fetch-Mode to fetch() calls; scripts do not); otherwise 'api'.
    """
    given = credentials.credentials.strip() if credentials is not None else None
    if not token_matches(request.app.state.token, given or None):
        raise ApiError(401, "unauthorized", "this command needs the control token: send 'Authorization: Bearer <token>'")
    declared = (x_armlab_controller or "").strip().lower()
    if declared in ("ui", "api"):
        return declared
    return "ui" if "sec-fetch-mode" in request.headers else "api"


StationDep = Annotated[Station, Depends(get_station)]
ControlAuth = Annotated[str, Depends(require_control)]
