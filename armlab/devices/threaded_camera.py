"""ThreadedCamera: the part every reader-thread camera backend shares.

A backend (OpenCV, RealSense) opens its device, then calls `_start_reader()`; its `_step()` captures
one frame and hands it to `_publish()`, or reports a failed read with `_read_failed()`. The newest
frame lives in a FrameBuffer, so read(), async_read() and read_latest() follow the Camera contract
the same way for every backend.
"""

from __future__ import annotations

import abc
import time

import numpy as np

from armlab.devices.camera import Camera, Frame, Intrinsics
from armlab.devices.frame_buffer import FrameBuffer, ReaderThread
from armlab.errors import DeviceNotConnectedError


class ThreadedCamera(Camera):
    """Camera with a reader thread and a newest-frame buffer. Subclasses set `config` (with
    read_timeout_s and max_consecutive_failures), implement `_step(stop) -> bool` and `__str__`."""

    def __init__(self) -> None:
        self._reader: ReaderThread | None = None
        self._buffer = FrameBuffer(str(self))
        self._intrinsics: Intrinsics | None = None
        self._sequence = 0
        self._failures = 0

    @property
    def is_connected(self) -> bool:
        return self._reader is not None

    @property
    def intrinsics(self) -> Intrinsics:
        if self._intrinsics is None:
            raise DeviceNotConnectedError(f"{self}: not connected: call connect() first")
        return self._intrinsics

    # -- reader thread ----------------------------------------------------------------------------

    @abc.abstractmethod
    def _step(self, stop) -> bool:
        """Capture one frame (the reader thread's body); False ends the thread."""

    def _start_reader(self, warmup_timeout_s: float) -> None:
        """Start the reader thread from a clean buffer and wait for the first frame (TimeoutError)."""
        self._buffer.reset()
        self._sequence = 0
        self._failures = 0
        self._reader = ReaderThread(f"{self}-reader", self._step)
        self._reader.start()
        self._buffer.wait_for_first(warmup_timeout_s)

    def _stop_reader(self) -> None:
        if self._reader is not None:
            self._reader.stop()
            self._reader = None

    def _publish(self, color_bgr: np.ndarray, depth_mm: np.ndarray | None) -> None:
        """Store a newly captured frame, stamped now (reader thread)."""
        self._failures = 0
        self._sequence += 1
        self._buffer.publish(
            Frame(
                color_bgr=color_bgr,
                depth_mm=depth_mm,
                timestamp_s=time.time(),
                sequence=self._sequence,
                intrinsics=self._intrinsics,
            )
        )

    def _read_failed(self, reason: str) -> bool:
        """Count a failed read; after too many in a row, end the stream. False ends the thread."""
        self._failures += 1
        if self._failures >= self.config.max_consecutive_failures:
            self._buffer.end(ConnectionError(f"{self}: {self._failures} consecutive failed reads; {reason}"))
            return False
        return True

    # -- reading ----------------------------------------------------------------------------------

    def _require_connected(self) -> None:
        if not self.is_connected:
            raise DeviceNotConnectedError(f"{self}: not connected: call connect() first")

    def read(self) -> Frame:
        """Block until the next new frame (at most config.read_timeout_s, then TimeoutError)."""
        self._require_connected()
        return self._buffer.read(self.config.read_timeout_s)

    def async_read(self, timeout_ms: float = 200.0) -> Frame:
        self._require_connected()
        return self._buffer.async_read(timeout_ms)

    def read_latest(self, max_age_ms: float = 500.0) -> Frame:
        self._require_connected()
        return self._buffer.read_latest(max_age_ms)
