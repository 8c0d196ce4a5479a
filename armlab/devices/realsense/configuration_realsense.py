"""RealSenseCameraConfig: an Intel RealSense colour + depth camera (e.g. the L515) via pyrealsense2."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from armlab.config import StrictModel


class RealSenseCameraConfig(StrictModel):
    """serial: the device's serial number (None = the first one found). Colour is BGR8 at width×height;
    with use_depth, depth (Z16) is aligned to colour and converted to millimetres. Intrinsics come from
    the device's factory calibration."""

    type: Literal["realsense"] = "realsense"
    serial: str | None = None
    width: int = Field(1280, gt=0, le=4096)
    height: int = Field(720, gt=0, le=4096)
    fps: int = Field(30, gt=0, le=300)
    use_depth: bool = True
    depth_width: int = Field(1024, gt=0, le=4096)
    depth_height: int = Field(768, gt=0, le=4096)
    warmup_timeout_s: float = Field(10.0, gt=0.0, le=60.0)
    read_timeout_s: float = Field(2.0, gt=0.0, le=60.0)
    frame_timeout_ms: int = Field(1000, gt=0, le=60000)
    max_consecutive_failures: int = Field(10, ge=1, le=10000)
