"""The station's camera and perception threads.

FrameSource is the camera's only reader: it publishes each new Frame into a NewestSlot that every
consumer (perception, the stream encoder, snapshots, calibration) reads at its own pace.
PerceptionLoop runs tag and block detection on the newest frame at its own rate (never on every
frame if it cannot keep up) and publishes a Perception snapshot.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armlab.devices.camera import Camera, Frame
from armlab.station.slots import NewestSlot

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Perception:
    """What the station currently sees: blocks (armlab.vision Block objects) and tags, from one frame."""

    blocks: tuple = ()
    tags: tuple = ()
    frame_sequence: int = -1
    capture_time_s: float = 0.0
    time_s: float = field(default_factory=time.time)


class _Worker:
    """A named daemon thread with a stop event and a bounded join."""

    name = "worker"

    def __init__(self) -> None:
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        if self._thread is not None:
            return
        self._stop.clear()
        self._thread = threading.Thread(target=self._run_safely, name=self.name, daemon=True)
        self._thread.start()

    def stop(self, timeout_s: float = 2.0) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
            self._thread = None

    def _run_safely(self) -> None:
        while not self._stop.is_set():
            try:
                self._run()
                return
            except Exception:  # noqa: BLE001 - a worker logs and restarts rather than dying silently
                log.exception("%s thread failed; restarting in 0.5 s", self.name)
                self._stop.wait(0.5)

    def _run(self) -> None:
        raise NotImplementedError


class FrameSource(_Worker):
    """Reads the camera (async_read: newest frame not yet consumed) and publishes into `slot`."""

    name = "station-camera"

    def __init__(self, camera: Camera, slot: NewestSlot[Frame]) -> None:
        super().__init__()
        self.camera = camera
        self.slot = slot

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                frame = self.camera.async_read(timeout_ms=200.0)
            except TimeoutError:
                continue
            self.slot.publish(frame)


class PerceptionLoop(_Worker):
    """Detects tags and blocks on the newest frame, at most `rate_hz` times per second.

    `get_calibration()` returns the current armlab.vision Calibration or None; blocks need it, tags
    do not. `config` is the armlab.vision PerceptionConfig.
    """

    name = "station-perception"

    def __init__(
        self,
        frames: NewestSlot[Frame],
        out: NewestSlot[Perception],
        get_calibration: Callable[[], Any],
        config: Any,
        rate_hz: float,
    ) -> None:
        super().__init__()
        self.frames = frames
        self.out = out
        self.get_calibration = get_calibration
        self.config = config
        self.period_s = 1.0 / rate_hz

    # Full tag searches this often; in between, tags are tracked in windows around their last centres.
    FULL_TAG_SEARCH_PERIOD_S = 2.0
    TRACK_HALF_SIZE_PX = 40

    def _run(self) -> None:
        from armlab.vision import detect_blocks
        from armlab.vision.tags import detect_tags, detect_tags_near, make_detector

        detector = make_detector(self.config.tags.dictionary)
        version, tags, last_full_s = 0, (), 0.0
        while not self._stop.is_set():
            frame, version = self.frames.wait_newer(version, timeout_s=0.5)
            if frame is None:
                continue
            started = time.monotonic()
            try:
                if tags and started - last_full_s < self.FULL_TAG_SEARCH_PERIOD_S:
                    centers = np.array([tag.center_px for tag in tags])
                    tracked = tuple(detect_tags_near(frame.color_bgr, centers, self.TRACK_HALF_SIZE_PX, detector))
                    tags = tracked if len(tracked) == len(tags) else ()
                if not tags or started - last_full_s >= self.FULL_TAG_SEARCH_PERIOD_S:
                    tags = tuple(detect_tags(frame.color_bgr, self.config, detector=detector))
                    last_full_s = started
            except ValueError as error:
                log.debug("tag detection failed: %s", error)
                tags = ()
            self.out.publish(analyse_frame(frame, tags, self.get_calibration(), self.config, detect_blocks))
            # At most the configured rate, and at most half of one core (sleep at least as long as we worked).
            elapsed = time.monotonic() - started
            self._stop.wait(max(self.period_s - elapsed, elapsed))


def analyse_frame(frame: Frame, tags: tuple, calibration: Any, config: Any, detect_blocks: Callable) -> Perception:
    """Blocks only with a calibration and a depth image (a failed detection logs and reports none)."""
    blocks: tuple = ()
    if calibration is not None and frame.depth_mm is not None:
        try:
            blocks = tuple(detect_blocks(frame.color_bgr, frame.depth_mm, calibration, config))
        except ValueError as error:
            log.debug("block detection failed: %s", error)
    return Perception(blocks=blocks, tags=tags, frame_sequence=frame.sequence, capture_time_s=frame.timestamp_s)
