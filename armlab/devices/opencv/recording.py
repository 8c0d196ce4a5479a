"""Writing BGR frames to a video file that OpenCVCamera can play back (MJPG in AVI: always available)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np


def write_video(path: str | Path, frames_bgr, fps: float = 30.0) -> Path:
    """Write (H, W, 3) uint8 BGR frames, all the same size, to `path` (.avi, MJPG); return the path."""
    frames = [np.asarray(frame) for frame in frames_bgr]
    if not frames:
        raise ValueError("write_video: no frames")
    height, width = frames[0].shape[:2]
    for index, frame in enumerate(frames):
        if frame.shape != (height, width, 3) or frame.dtype != np.uint8:
            raise ValueError(f"write_video: frame {index} is {frame.shape} {frame.dtype}, expected ({height}, {width}, 3) uint8")
    if not fps > 0:
        raise ValueError(f"write_video: fps must be > 0, got {fps}")
    path = Path(path)
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), float(fps), (width, height))
    if not writer.isOpened():
        raise OSError(f"write_video: cannot open {path} for writing")
    try:
        for frame in frames:
            writer.write(frame)
    finally:
        writer.release()
    return path
