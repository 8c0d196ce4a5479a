"""What the gate sees: fresh frames and perception for skills, the first frame after a change, and the detections
(marked stale while the camera is lost).

Owned by core.Station (station.perceiver). Frames come from the camera thread (FrameSource) and perception from the
perception thread (PerceptionLoop), both started by the station; given `capture_now` (a station that runs no threads:
the fast-mode simulation renders a frame when asked) a frame is captured and analysed when a skill asks instead.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from armlab.devices.camera import Frame
from armlab.station.jobs import JobContext
from armlab.station.perception import FrameSource, Perception, PerceptionLoop, analyse_frame
from armlab.station.slots import NewestSlot
from armlab.station.telemetry import Detections
from armlab.vision.pipeline import PerceptionPipeline


class Perceiver:
    """The frames and perception slots, the camera and perception threads (or capture on demand), fresh frames and
    perception, detections.

    get_config(): armlab.vision's PerceptionConfig; get_calibration(): the calibration in use (or None);
    get_color_model(): the station's colour model; camera_lost(): why the camera is lost (the latch's lost
    devices), else None; capture_now(): a frame rendered now, where no camera thread runs (None: the thread)."""

    def __init__(self, get_config: Callable[[], Any], arm_model: Any, get_calibration: Callable[[], Any],
                 get_color_model: Callable[[], Any], camera_lost: Callable[[], str | None], camera_timeout_s: float,
                 capture_now: Callable[[], Frame] | None = None) -> None:
        self._config, self._arm_model, self._calibration = get_config, arm_model, get_calibration
        self._color_model, self._camera_lost, self._camera_timeout_s = get_color_model, camera_lost, camera_timeout_s
        self._capture_now = capture_now
        self.frames: NewestSlot[Frame] = NewestSlot()
        self.results: NewestSlot[Perception] = NewestSlot()
        self._frame_source: FrameSource | None = None  # the camera thread, once threads() made it
        self._pipeline: Any = None  # the pipeline of perception on demand (capture_now)

    def threads(self, camera: Any, arm: Any, gripper: Any, rate_hz: float, get_check_calibration: Callable[[], Any],
                on_check: Callable) -> list:
        """The camera and perception threads, not started (none with capture_now); on_check: the camera-moved check's."""
        if self._capture_now is not None:
            return []
        self._frame_source = FrameSource(camera, self.frames, arm, gripper)
        return [self._frame_source, PerceptionLoop(
            self.frames, self.results, self._calibration, self._config(), rate_hz, self._arm_model,
            get_check_calibration=get_check_calibration, on_check=on_check, get_color_model=self._color_model,
        )]

    @property
    def on_demand(self) -> bool:
        """Frames are captured when asked (capture_now): no camera thread draws them."""
        return self._capture_now is not None

    def wait_for_new_frame(self, version: int, timeout_s: float) -> None:
        """Wait up to timeout_s for the camera thread to publish a frame newer than `version` (frames.get()'s
        version); at once with frames on demand (the next one asked for is new)."""
        if not self.on_demand:
            self.frames.wait_newer(version, timeout_s=timeout_s)

    def camera_problem(self) -> str | None:
        """Why the camera thread gets no frames (it raised, or none for camera_timeout_s), else None (also without one)."""
        return None if self._frame_source is None else self._frame_source.health(self._camera_timeout_s)

    # Detections -------------------------------------------------------------------------------------

    def detections(self) -> Detections:
        """The newest detected blocks (GET /api/detections serialises them); none, with the reason, while the
        camera is lost or perception is older than camera_timeout_s."""
        perception, _ = self.results.get()
        if perception is None:
            return Detections((), time.time(), -1)
        stale_reason = self.stale_reason(perception)
        blocks = () if stale_reason else perception.seen_blocks()
        return Detections(blocks, perception.time_s, perception.frame_sequence, stale_reason)

    def stale_reason(self, perception: Perception) -> str | None:
        camera_lost = self._camera_lost()
        if camera_lost is not None:
            return f"the camera is lost ({camera_lost})"
        age_s = time.time() - perception.capture_time_s
        if self._capture_now is None and age_s > self._camera_timeout_s:
            return f"the newest perception is {age_s:.1f} s old"
        return None

    # Fresh frames and perception --------------------------------------------------------------------

    def fresh_frame(self, timeout_s: float = 2.0, max_age_s: float = 2.0) -> Frame:
        """A camera frame taken now (capture_now: rendered now; else the newest, waiting for a newer
        one when it is older than max_age_s). TimeoutError (a device error) when the camera gives none."""
        if self._capture_now is not None:
            frame = self._capture_now()
            self.frames.publish(frame)
            return frame
        frame, version = self.frames.get()
        if frame is None or time.time() - frame.timestamp_s > max_age_s:
            frame, _ = self.frames.wait_newer(version, timeout_s)
        if frame is None or time.time() - frame.timestamp_s > max_age_s + timeout_s:
            raise TimeoutError(f"no fresh camera frame within {timeout_s} s: is the camera running?")
        return frame

    def frame_after(self, since_s: float, timeout_s: float = 3.0) -> Frame:
        """The first camera frame whose picture was taken at or after wall time since_s (capture_now: rendered
        now). What a command that follows a change (a scene, the arm's arrival, a request) must look at: the
        newest frame may show the world a second ago, more on a busy machine. TimeoutError when the camera gives
        none in timeout_s."""
        if self._capture_now is not None:
            return self.fresh_frame()
        deadline = time.monotonic() + timeout_s
        frame, version = self.frames.get()
        while frame is None or frame.timestamp_s < since_s:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(f"no camera frame newer than {time.time() - since_s:.1f} s ago within {timeout_s:g} s: "
                                   "is the camera running?")
            frame, version = self.frames.wait_newer(version, remaining)
        return frame

    def fresh_perception(self, ctx: JobContext | None = None, timeout_s: float = 5.0) -> Perception:
        """Perception of a frame captured after this call began (so after the last motion ended).

        capture_now: captured and analysed now. Otherwise: waits for the perception thread (ctx: a job's cancel
        is checked while it waits)."""
        if self._capture_now is not None:
            if self._pipeline is None:
                self._pipeline = PerceptionPipeline(self._config(), arm_model=self._arm_model)
            self._pipeline.color_model = self._color_model()
            frame = self.fresh_frame()
            previous, _ = self.results.get()
            perception = analyse_frame(self._pipeline, frame, self._calibration(), previous.surface_depth_mm if previous else None,
                                       previous.surface_time_s if previous else None)
            self.results.publish(perception)
            return perception
        asked_s = time.time()
        deadline = time.monotonic() + timeout_s
        _, version = self.results.get()
        while time.monotonic() < deadline:
            if ctx is not None:
                ctx.check()
            perception, version = self.results.wait_newer(version, timeout_s=0.2)
            if perception is not None and perception.capture_time_s >= asked_s:
                return perception
        raise TimeoutError(f"no perception of a fresh frame within {timeout_s} s: is the camera running?")
