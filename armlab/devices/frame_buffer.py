"""FrameBuffer: the newest-frame store shared by threaded cameras (one writer thread, many readers).

It holds only the newest Frame ("newest value wins") and implements the Camera read semantics:
read() waits for a frame newer than the call, async_read() returns the newest frame it has not
returned yet, read_latest() never waits and refuses stale frames. The writer can mark the stream
ended (end of a video file, device lost) so waiting readers get that error instead of a timeout.
No SDK imports: the OpenCV and RealSense backends (and any other) reuse it.
"""

from __future__ import annotations

import threading
import time

from armlab.devices.camera import Frame


class FrameBuffer:
    """Thread-safe newest-frame holder; `owner` (the camera) prefixes every error message."""

    def __init__(self, owner: str) -> None:
        self._owner = owner
        self._condition = threading.Condition()
        self._frame: Frame | None = None
        self._async_sequence = -1
        self._end_error: Exception | None = None

    def reset(self) -> None:
        """Forget frames and errors (before a new connection)."""
        with self._condition:
            self._frame = None
            self._async_sequence = -1
            self._end_error = None

    def publish(self, frame: Frame) -> None:
        """Store a new frame and wake the readers (writer thread)."""
        with self._condition:
            self._frame = frame
            self._condition.notify_all()

    def end(self, error: Exception) -> None:
        """Mark the stream ended: readers that would wait for a new frame get `error` instead."""
        with self._condition:
            self._end_error = error
            self._condition.notify_all()

    @property
    def ended(self) -> Exception | None:
        with self._condition:
            return self._end_error

    @property
    def newest(self) -> Frame | None:
        with self._condition:
            return self._frame

    def _wait_for(self, after_sequence: int, timeout_s: float) -> Frame:
        """Wait until a frame with sequence > after_sequence exists (caller holds the lock)."""
        deadline = time.monotonic() + timeout_s
        while self._frame is None or self._frame.sequence <= after_sequence:
            if self._end_error is not None:
                raise self._end_error
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(f"{self._owner}: no new frame within {timeout_s * 1000:.0f} ms")
            self._condition.wait(remaining)
        return self._frame

    def wait_for_first(self, timeout_s: float) -> Frame:
        """Wait until any frame exists, without consuming it (connect-time warm-up)."""
        with self._condition:
            return self._wait_for(-1, timeout_s)

    def read(self, timeout_s: float) -> Frame:
        """The first frame captured after this call (marks it consumed for async_read too)."""
        with self._condition:
            current = -1 if self._frame is None else self._frame.sequence
            frame = self._wait_for(current, timeout_s)
            self._async_sequence = max(self._async_sequence, frame.sequence)
            return frame

    def async_read(self, timeout_ms: float) -> Frame:
        """The newest frame not yet returned by async_read/read, waiting up to timeout_ms."""
        if not timeout_ms >= 0:
            raise ValueError(f"{self._owner}: timeout_ms must be ≥ 0, got {timeout_ms}")
        with self._condition:
            frame = self._wait_for(self._async_sequence, timeout_ms / 1000.0)
            self._async_sequence = frame.sequence
            return frame

    def read_latest(self, max_age_ms: float) -> Frame:
        """The newest frame without waiting; TimeoutError if there is none or it is older than max_age_ms."""
        if not max_age_ms >= 0:
            raise ValueError(f"{self._owner}: max_age_ms must be ≥ 0, got {max_age_ms}")
        with self._condition:
            frame = self._frame
        if frame is None:
            raise TimeoutError(f"{self._owner}: no frame captured yet")
        age_ms = (time.time() - frame.timestamp_s) * 1000.0
        if age_ms > max_age_ms:
            raise TimeoutError(f"{self._owner}: newest frame is {age_ms:.0f} ms old (max_age_ms={max_age_ms:.0f})")
        return frame


class ReaderThread:
    """A daemon thread calling `step()` until stopped; stop() joins with a bounded timeout."""

    def __init__(self, name: str, step, join_timeout_s: float = 2.0) -> None:
        self._step = step
        self._stop = threading.Event()
        self._join_timeout_s = join_timeout_s
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            if self._step(self._stop) is False:
                return

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> bool:
        """Ask the thread to stop and wait for it; False if it did not end within the join timeout."""
        self._stop.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(self._join_timeout_s)
        return not self._thread.is_alive()

    @property
    def alive(self) -> bool:
        return self._thread.is_alive()
