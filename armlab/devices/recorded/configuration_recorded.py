"""RecordedCameraConfig: recorded RGB-D frames (a folder of PNG pairs or a ROS bag) played as a live camera."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from armlab.config import StrictModel


class RecordedCameraConfig(StrictModel):
    """source: a folder of image_<name>.png + depth_<name>.png pairs (16-bit mm depth aligned to colour), or a
    ROS bag (a rosbag2 folder with metadata.yaml, a .db3/.mcap file, or a ROS 1 .bag).

    intrinsics: a file with K, dist and image_size (or a ROS camera_info/calibration YAML); without it a
    folder's own intrinsics.json (else the one file in it holding intrinsics) and a bag's camera_info are used,
    and a recording with none of these is refused. frame: hold the pair of this name (folders only).
    fps: frames published per second, so the station sees a live camera (a held pair is re-sent).
    seconds_per_pair: a folder shows each pair this long, then the next. playback_speed: a bag plays at its
    recorded timing times this. loop: start again at the end (else end-of-stream, EOFError).
    color_topic, depth_topic, info_topic: a bag's topics (None: found by name); max_skew_s: colour and depth
    stamps further apart are not a pair.
    """

    type: Literal["recorded"] = "recorded"
    source: str
    intrinsics: str | None = None
    frame: str | None = None
    fps: float = Field(10.0, gt=0.0, le=120.0)
    seconds_per_pair: float = Field(5.0, gt=0.0, le=3600.0)
    playback_speed: float = Field(1.0, gt=0.0, le=100.0)
    loop: bool = True
    color_topic: str | None = None
    depth_topic: str | None = None
    info_topic: str | None = None
    max_skew_s: float = Field(0.02, ge=0.0, le=1.0)
    warmup_timeout_s: float = Field(10.0, gt=0.0, le=60.0)
    read_timeout_s: float = Field(2.0, gt=0.0, le=60.0)
    max_consecutive_failures: int = Field(10, ge=1, le=10000)

    @model_validator(mode="after")
    def _check(self) -> RecordedCameraConfig:
        if not self.source.strip():
            raise ValueError("source: empty path (a folder of image_*.png + depth_*.png, or a ROS bag)")
        if self.frame is not None and not self.frame.strip():
            raise ValueError("frame: empty name (the <name> of image_<name>.png)")
        return self
