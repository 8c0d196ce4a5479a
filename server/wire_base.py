"""The base of the wire models (server/models.py and the modules it gathers): request and response base
classes, the value types with their sanity bounds, and the error codes.

Field names carry their units (SI). Requests forbid unknown fields and NaN/infinity, so malformed
input is refused with a clear 422 before the station sees it.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

Vector3 = list[float]
View = Literal["color", "depth", "topdown"]
Layer = Literal["tags", "detections", "grid"]
ERROR_CODES = (
    "wrong_state",
    "unreachable",
    "unsafe",
    "invalid",
    "not_found",
    "not_calibrated",
    "unauthorized",
    "forbidden",
    "not_controller",
    "needs_confirmation",
    "no_arm",
    "device",
    "disk_full",
    "stale_plan",
    "internal",
)

# Sanity bounds of request values, stated in the OpenAPI schema. The station applies the real limits
# (joint limits, reach, config max_moving_time_s) on top; these only keep absurd numbers out.
ANGLE_LIMIT_RAD = 2.0 * math.pi
POSITION_LIMIT_M = 5.0  # the workcell is ~1 m across; scene objects are refused beyond 5 m too
MOVING_TIME_LIMIT_S = 3600.0
PIXEL_LIMIT = 100_000.0
SQLITE_INTEGER_MAX = 2**63 - 1  # program ids are SQLite INTEGERs

Angle = Annotated[float, Field(ge=-ANGLE_LIMIT_RAD, le=ANGLE_LIMIT_RAD, description="radians, |angle| <= 2π")]
Coordinate = Annotated[float, Field(ge=-POSITION_LIMIT_M, le=POSITION_LIMIT_M, description="metres, |value| <= 5")]
Position = Annotated[list[Coordinate], Field(min_length=3, max_length=3)]
MovingTime = Annotated[float, Field(gt=0.0, le=MOVING_TIME_LIMIT_S, description="seconds; the station refuses more than its configured maximum")]
Velocity = Annotated[float, Field(ge=-ANGLE_LIMIT_RAD, le=ANGLE_LIMIT_RAD, description="rad/s, |value| <= 2π; the station applies the joint limits")]
Pixel = Annotated[float, Field(ge=0.0, le=PIXEL_LIMIT, description="pixel coordinate in the colour image")]
SpeedPercent = Annotated[float, Field(ge=10.0, le=100.0, description="speed override, % of the configured speed (10-100)")]
ProgramId = Annotated[int, Field(ge=0, le=SQLITE_INTEGER_MAX, description="a program id (SQLite integer)")]


class Request(BaseModel):
    """Base of every request: strict types (no bool/number/string coercion), no unknown fields, no NaN/inf."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


class Wire(BaseModel):
    model_config = ConfigDict(allow_inf_nan=True)
