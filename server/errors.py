"""Library errors → HTTP, in one place. Every error body is {"error": {"code", "message", "allowed"?}}."""

from __future__ import annotations

import logging

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from armlab.errors import (
    ArmlabError,
    CalibrationUntrusted,
    CommandRefused,
    DeviceFault,
    InvalidInput,
    NeedsConfirmation,
    NoArmError,
    NotController,
    PlanNotFound,
    PlanNotYours,
    PlanRefused,
    PlanStale,
    RefusedByCheck,
    ShuttingDown,
)
from armlab.kinematics import Unreachable
from armlab.motion.safety import UnsafeTrajectory
from armlab.recording import DiskFull
from armlab.station.core import NotCalibrated
from armlab.store import NotFound
from server.models import ErrorResponse

log = logging.getLogger(__name__)

_HTTP_CODES = {400: "invalid", 401: "unauthorized", 403: "forbidden", 404: "not_found", 405: "invalid", 409: "wrong_state"}


class ApiError(Exception):
    """An error a route raises directly with its HTTP status and wire code."""

    def __init__(self, status_code: int, code: str, message: str, allowed: list[str] | None = None) -> None:
        super().__init__(message)
        self.status_code, self.code, self.message, self.allowed = status_code, code, message, allowed


def error_response(status_code: int, code: str, message: str, allowed: list[str] | None = None, headers=None,
                   **named: str | list[float] | None) -> JSONResponse:
    body: dict = {"code": code, "message": message}
    if allowed is not None:
        body["allowed"] = allowed
    body.update({key: value for key, value in named.items() if value is not None})
    return JSONResponse({"error": body}, status_code=status_code, headers=headers)


def _validation_message(error: RequestValidationError) -> str:
    parts = []
    for item in error.errors():
        location = ".".join(str(part) for part in item.get("loc", ()) if part != "body")
        if item.get("type") == "json_invalid":
            return f"the request body is not valid JSON: {item.get('ctx', {}).get('error', item.get('msg'))}"
        parts.append(f"{location or 'body'}: {item.get('msg')}")
    return "invalid request: " + "; ".join(parts)


def error_status(error: Exception) -> tuple[int, str]:
    """HTTP status and wire code for an exception (the first row of ERROR_STATUS it is an instance of)."""
    for error_class, status_code, code in ERROR_STATUS:
        if isinstance(error, error_class):
            return status_code, code
    return 500, "internal"


# The library's error hierarchy (armlab.errors) → HTTP status and wire code, most specific first. Anything
# not listed, a bare ValueError included (a bug, e.g. numpy's), is 500 "internal" with its traceback logged.
ERROR_STATUS: tuple[tuple[type[BaseException], int, str], ...] = (
    (ShuttingDown, 503, "device"),  # a refusal, but one that says the station is going away
    (NoArmError, 409, "no_arm"),
    (CommandRefused, 409, "wrong_state"),
    (NotController, 409, "not_controller"),
    (NeedsConfirmation, 409, "needs_confirmation"),
    (NotCalibrated, 409, "not_calibrated"),
    (CalibrationUntrusted, 409, "not_calibrated"),
    (NotFound, 404, "not_found"),
    (PlanNotFound, 404, "not_found"),
    (PlanStale, 409, "stale_plan"),
    (PlanNotYours, 409, "not_controller"),
    (DiskFull, 507, "disk_full"),  # a recording cannot start: too little free disk
    (Unreachable, 422, "unreachable"),
    (UnsafeTrajectory, 422, "unsafe"),
    (PlanRefused, 422, "invalid"),
    (RefusedByCheck, 409, "wrong_state"),  # any other check's refusal: not allowed now
    (InvalidInput, 422, "invalid"),
    (ValidationError, 422, "invalid"),  # a pydantic model of the library refused a value (a scene, a workcell)
    (DeviceFault, 503, "device"),
    (ConnectionError, 503, "device"),  # an OSError of a device's transport
    (TimeoutError, 503, "device"),
)


# Error statuses every operation documents (all with the ErrorResponse body); 401 only where the
# control token is required, 400 only where there is a request body. 422 replaces FastAPI's default
# HTTPValidationError, which this API never sends.
_DOCUMENTED_ERRORS = {
    "400": "the request body could not be read (not UTF-8)",
    "401": "the control token is missing or wrong",
    "403": "refused: a Host this station does not serve, or a foreign Origin",
    "404": "no such item (or a damaged one, left out)",
    "409": "not allowed in the current state (allowed commands listed), not calibrated or the calibration not trusted "
    "(the reason), another client controls the station (named), needs confirm: true, needs an arm the station "
    "does not have (no_arm), or a motion plan that is stale or another controller's (stale_plan with its reason)",
    "422": "invalid input, or an unreachable or unsafe target (the part named); nothing moved",
    "503": "a device is not connected, timed out or is still lost, or the station is shutting down",
}


def document_error_responses(schema: dict) -> dict:
    """Add the documented error responses (ErrorResponse body) to every operation of an OpenAPI schema."""
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    definitions = ErrorResponse.model_json_schema(ref_template="#/components/schemas/{model}")
    components.update(definitions.pop("$defs", {}))
    components["ErrorResponse"] = definitions
    body = {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorResponse"}}}
    for path_item in schema.get("paths", {}).values():
        for operation in path_item.values():
            responses = operation.setdefault("responses", {})
            for status, description in _DOCUMENTED_ERRORS.items():
                if (status != "401" or operation.get("security")) and (status != "400" or "requestBody" in operation):
                    responses[status] = {"description": description, "content": body}
    for unused in ("HTTPValidationError", "ValidationError"):
        components.pop(unused, None)
    return schema


def install_error_handlers(app: FastAPI) -> None:
    build_openapi = app.openapi

    def openapi() -> dict:
        if app.openapi_schema is None:
            app.openapi_schema = document_error_responses(build_openapi())
        return app.openapi_schema

    app.openapi = openapi  # type: ignore[method-assign]

    @app.exception_handler(ApiError)
    async def _api_error(_: Request, error: ApiError) -> JSONResponse:
        return error_response(error.status_code, error.code, error.message, error.allowed)

    @app.exception_handler(RequestValidationError)
    async def _invalid(_: Request, error: RequestValidationError) -> JSONResponse:
        return error_response(422, "invalid", _validation_message(error))

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, error: StarletteHTTPException) -> JSONResponse:
        code = _HTTP_CODES.get(error.status_code, "invalid")
        message = {
            404: f"nothing at {request.method} {request.url.path}",
            405: f"{request.method} is not allowed on {request.url.path}",
        }.get(error.status_code, str(error.detail))
        return error_response(error.status_code, code, message, headers=getattr(error, "headers", None))

    async def _library(request: Request, error: Exception) -> JSONResponse:
        status_code, code = error_status(error)
        if status_code == 500:
            log.error("internal error in %s %s", request.method, request.url.path, exc_info=error)
            return error_response(500, code, f"internal error ({type(error).__name__}); the server log has the traceback")
        allowed = error.allowed if isinstance(error, CommandRefused) else None
        reason = error.reason if isinstance(error, PlanStale) else None
        unsafe = error if isinstance(error, UnsafeTrajectory) else None
        return error_response(status_code, code, str(error), allowed, reason=reason, part=getattr(unsafe, "part", None),
                              at_q_rad=getattr(unsafe, "at_q_rad", None))

    # Registered per base class so they are handled inside the app (a bare Exception handler runs in
    # Starlette's outermost middleware, which logs and re-raises).
    for error_class in (
        ArmlabError, ValueError, ConnectionError, TimeoutError, Exception
    ):
        app.add_exception_handler(error_class, _library)
