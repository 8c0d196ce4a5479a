"""OpenCVCamera: a webcam or a video file behind the Camera interface (colour only, no depth).

A daemon reader thread pulls frames from cv2.VideoCapture and keeps only the newest (ThreadedCamera).
A video file is paced at its frame rate and loops by default; with loop=False the camera reports
EOFError once the last frame is consumed. connect() is all-or-nothing: on any failure it releases
the capture and stops the thread, so calling connect() again works. Messages start with str(camera).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.devices.opencv.configuration_opencv import OpenCVCameraConfig
from armlab.devices.threaded_camera import ThreadedCamera
from armlab.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError


def nominal_intrinsics(width: int, height: int, hfov_deg: float) -> Intrinsics:
    """Pinhole intrinsics for a frame size and horizontal field of view: square pixels, centred, no distortion."""
    fx = (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)
    return Intrinsics(width=width, height=height, fx=fx, fy=fx, cx=(width - 1) / 2.0, cy=(height - 1) / 2.0)


class OpenCVCamera(ThreadedCamera):
    """cv2.VideoCapture camera with a reader thread; see OpenCVCameraConfig for the options."""

    def __init__(self, config: OpenCVCameraConfig) -> None:
        self.config = config
        super().__init__()
        self._capture: cv2.VideoCapture | None = None
        self._period_s = 0.0
        self._next_capture_s = 0.0

    def __str__(self) -> str:
        return f"OpenCVCamera({self.config.source})"

    @property
    def intrinsics(self) -> Intrinsics:
        if self._intrinsics is None:
            raise DeviceNotConnectedError(f"{self}: not connected (intrinsics need the frame size): call connect() first")
        return self._intrinsics

    # -- connection -------------------------------------------------------------------------------

    def connect(self) -> None:
        """Open the source, check the frame size, start the reader thread and wait for a first frame."""
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self}: already connected; call close() before connecting again")
        try:
            self._open()
            self._next_capture_s = time.monotonic()
            self._start_reader(self.config.warmup_timeout_s)
        except BaseException as error:
            self._teardown()
            if isinstance(error, TimeoutError):
                raise ConnectionError(f"{self}: no frame within {self.config.warmup_timeout_s:.1f} s of opening") from error
            raise

    def _open(self) -> None:
        config = self.config
        if config.is_file and not Path(config.source).exists():
            raise ConnectionError(f"{self}: video file not found: {config.source}")
        capture = cv2.VideoCapture(config.source)
        self._capture = capture
        if not capture.isOpened():
            raise ConnectionError(f"{self}: cv2.VideoCapture could not open the source")
        if not config.is_file:
            if config.width is not None:
                capture.set(cv2.CAP_PROP_FRAME_WIDTH, config.width)
                capture.set(cv2.CAP_PROP_FRAME_HEIGHT, config.height)
            if config.fps is not None:
                capture.set(cv2.CAP_PROP_FPS, config.fps)
        ok, image = capture.read()
        if not ok or image is None:
            raise ConnectionError(f"{self}: the source opened but returned no frame")
        height, width = image.shape[:2]
        if config.width is not None and (width, height) != (config.width, config.height):
            raise ConnectionError(
                f"{self}: frames are {width}x{height}, the config asks for {config.width}x{config.height}"
            )
        if config.is_file:
            capture.set(cv2.CAP_PROP_POS_FRAMES, 0)  # the thread starts from the first frame
        source_fps = capture.get(cv2.CAP_PROP_FPS)
        fps = config.fps or (source_fps if source_fps and math.isfinite(source_fps) and source_fps > 0 else 30.0)
        self._period_s = 1.0 / fps
        if config.intrinsics is not None:
            known = config.intrinsics
            self._intrinsics = Intrinsics(width, height, known.fx, known.fy, known.cx, known.cy, tuple(known.dist))
        else:
            self._intrinsics = nominal_intrinsics(width, height, config.nominal_hfov_deg)

    def close(self) -> None:
        """Stop the reader thread and release the capture. Safe to call twice."""
        self._teardown()

    def _teardown(self) -> None:
        self._stop_reader()
        if self._capture is not None:
            self._capture.release()
            self._capture = None
        self._intrinsics = None

    # -- reader thread ----------------------------------------------------------------------------

    def _step(self, stop) -> bool:
        """One capture: pace to the frame rate (files), read, publish; False ends the thread."""
        delay = self._next_capture_s - time.monotonic()
        if delay > 0 and stop.wait(delay):
            return False
        self._next_capture_s = max(self._next_capture_s + self._period_s, time.monotonic() - self._period_s)
        ok, image = self._capture.read()
        if not ok or image is None:
            if self.config.is_file:
                if not self.config.loop:
                    self._buffer.end(EOFError(f"{self}: end of the video file (loop is off)"))
                    return False
                self._capture.set(cv2.CAP_PROP_POS_FRAMES, 0)
                ok, image = self._capture.read()
            if not ok or image is None:
                return self._read_failed("device lost")
        self._publish(np.ascontiguousarray(image), None)
        return True
