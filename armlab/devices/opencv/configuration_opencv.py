"""OpenCVCameraConfig: a webcam (device index) or a video file read through cv2.VideoCapture."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from armlab.config import StrictModel


class IntrinsicsConfig(StrictModel):
    """Pinhole intrinsics in pixels of the configured frame size, OpenCV distortion (k1, k2, p1, p2, k3)."""

    fx: float = Field(gt=0.0)
    fy: float = Field(gt=0.0)
    cx: float = Field(ge=0.0)
    cy: float = Field(ge=0.0)
    dist: tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)


class OpenCVCameraConfig(StrictModel):
    """A colour-only camera read by cv2.VideoCapture.

    source: a device index (0 = first webcam) or a video file path. width/height/fps: requested from a
    device; for a video file they must match the file if given (fps paces playback: default the
    file's own rate). loop: a video file restarts at its end; with loop false the camera reports
    end-of-stream (EOFError) once the last frame has been consumed. intrinsics: measured values;
    when absent they are derived from the frame size and nominal_hfov_deg (square pixels, centred).
    """

    type: Literal["opencv"] = "opencv"
    source: int | str
    width: int | None = Field(None, gt=0, le=8192)
    height: int | None = Field(None, gt=0, le=8192)
    fps: float | None = Field(None, gt=0.0, le=1000.0)
    loop: bool = True
    intrinsics: IntrinsicsConfig | None = None
    nominal_hfov_deg: float = Field(69.0, gt=1.0, lt=179.0)
    warmup_timeout_s: float = Field(5.0, gt=0.0, le=60.0)
    read_timeout_s: float = Field(2.0, gt=0.0, le=60.0)
    max_consecutive_failures: int = Field(30, ge=1, le=10000)

    @model_validator(mode="after")
    def _check(self) -> OpenCVCameraConfig:
        if isinstance(self.source, int) and self.source < 0:
            raise ValueError(f"source: a device index must be ≥ 0, got {self.source}")
        if isinstance(self.source, str) and not self.source.strip():
            raise ValueError("source: empty path")
        if (self.width is None) != (self.height is None):
            raise ValueError("width and height must be given together")
        if self.intrinsics is not None and (self.width is None or self.height is None):
            raise ValueError("intrinsics need width and height (the frame size they were measured at)")
        return self

    @property
    def is_file(self) -> bool:
        return isinstance(self.source, str)
