"""The station's camera and perception threads.

FrameSource is the camera's only reader: it publishes each new Frame into a NewestSlot that every
consumer (perception, the stream encoder, snapshots, calibration) reads at its own pace.
PerceptionLoop runs armlab.vision's PerceptionPipeline (tags, blocks) on the newest frame at its own
rate (skipping frames it cannot keep up with) and publishes a Perception snapshot. Each frame carries
the arm joints measured when it was taken and whether the gripper was closed (from the sim camera,
else read here from the arm and gripper), so perception can filter the robot, and a block it holds,
out of the image (armlab.vision.self_filter).
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from armlab.devices.arm import Arm
from armlab.devices.camera import Camera, Frame
from armlab.devices.gripper import Gripper
from armlab.station.slots import NewestSlot
from armlab.vision.block import Block
from armlab.vision.drift import DriftMonitor
from armlab.vision.pipeline import PerceptionPipeline

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Perception:
    """What the station currently sees: blocks (armlab.vision Block objects) and tags, from one frame.

    arm_joints_rad: the arm's measured joints when that frame was captured (None if unknown).
    robot_mask: (H, W) bool pixels of that frame that belong to the robot (the self-filter's mask;
    None without joints, arm model or calibration), e.g. for pixel-to-world to ignore the arm's depth.
    surface_depth_mm: (H, W) uint16 the newest depth of each pixel while the robot did not cover it
    (earlier frames' where it does now; 0 = never seen): what pixel-to-world falls back on under the arm.
    surface_time_s: (H, W) the capture time of each pixel's surface_depth_mm (0 = never seen): a remembered
    depth older than the last motion through its spot is not used (issue 21).
    """

    blocks: tuple[Block, ...] = ()
    tags: tuple = ()
    frame_sequence: int = -1
    capture_time_s: float = 0.0
    time_s: float = field(default_factory=time.time)
    arm_joints_rad: tuple[float, ...] | None = None
    robot_mask: np.ndarray | None = field(default=None, repr=False)
    surface_depth_mm: np.ndarray | None = field(default=None, repr=False)
    surface_time_s: np.ndarray | None = field(default=None, repr=False)
    camera_warning: str | None = None  # "camera moved: recalibrate (...)" while the calibration no longer fits the board tags

    def seen_blocks(self) -> tuple[Block, ...]:
        """The blocks in detection order, each stamped with this frame's capture time (seen_time_s) unless it has its own."""
        return tuple(block if block.seen_time_s is not None else replace(block, seen_time_s=self.capture_time_s)
                     for block in self.blocks)


DEVICE_ERRORS = (ConnectionError, TimeoutError, OSError)  # a device failed, as opposed to a bad request
CAMERA_RETRY_S = 0.5  # a camera that raised is read again after this long


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

    def request_stop(self) -> None:
        """Ask the thread to end (returns at once; stop() also joins)."""
        self._stop.set()

    def stop(self, timeout_s: float = 2.0) -> bool:
        """Stop and join (bounded); True if the thread has ended (or never ran)."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is None:
            return True
        thread.join(timeout_s)
        return not thread.is_alive()

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
    """Reads the camera (async_read: newest frame not yet consumed) and publishes into `slot`.

    arm, gripper: when given, a frame whose camera left arm_joints_rad (gripper_closed) None gets the
    arm's measured joints (the gripper's command), read as soon as the frame arrives (the sim camera
    fills both exactly at render time)."""

    name = "station-camera"

    def __init__(self, camera: Camera, slot: NewestSlot[Frame], arm: Arm | None = None, gripper: Gripper | None = None) -> None:
        super().__init__()
        self.camera = camera
        self.slot = slot
        self.arm = arm
        self.gripper = gripper
        self.error: str | None = None  # the camera's last failure, until it delivers a frame again
        self.last_frame_monotonic_s = time.monotonic()  # when the newest frame arrived (start counts as one)

    def health(self, timeout_s: float) -> str | None:
        """None while the camera delivers, else why not: it raised, or no frame for more than timeout_s."""
        if self.error is not None:
            return self.error
        age_s = time.monotonic() - self.last_frame_monotonic_s
        return f"no frame for {age_s:.1f} s" if age_s > timeout_s else None

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                frame = self.camera.async_read(timeout_ms=200.0)
            except TimeoutError:
                continue
            except Exception as error:  # noqa: BLE001 - any camera failure is reported (the station faults), then retried
                if self.error is None:
                    log.warning("%s: camera failed: %s", self.name, error)
                self.error = f"{type(error).__name__}: {error}"
                self._stop.wait(CAMERA_RETRY_S)
                continue
            self.error = None
            self.last_frame_monotonic_s = time.monotonic()
            self.slot.publish(with_robot_state(frame, self.arm, self.gripper))


def with_robot_state(frame: Frame, arm: Arm | None, gripper: Gripper | None = None) -> Frame:
    """The frame with the arm's measured joints and whether the gripper is commanded closed, where the
    camera left them None (each unchanged without its device or when the device cannot be read:
    perception then runs without the self-filter, or assumes a block may be held)."""
    changes: dict = {}
    try:
        if frame.arm_joints_rad is None and arm is not None:
            changes["arm_joints_rad"] = np.array(arm.read_joint_state().position_rad, dtype=float)
        if frame.gripper_closed is None and gripper is not None:
            changes["gripper_closed"] = gripper.read_state().command == "grasp"
    except DEVICE_ERRORS as error:
        log.debug("no robot state for frame %d: %s", frame.sequence, error)
    return replace(frame, **changes) if changes else frame


class PerceptionLoop(_Worker):
    """Detects tags and blocks on the newest frame, at most `rate_hz` times per second.

    `get_calibration()` returns the current armlab.vision Calibration or None; blocks need it, tags
    do not. `config` is the armlab.vision PerceptionConfig. `arm_model` (armlab.kinematics ArmModel)
    turns on the robot self-filter for frames that carry the arm's joints.
    `get_check_calibration()` (default: get_calibration) is the calibration the camera-moved check
    compares the board tags with (a restored one is checked before it is used); after each check
    `on_check(calibration, drift_px, warning, perception)` is called, if given. `get_color_model()`
    (armlab.vision.colors ColorModel) names block colours, read each frame (None: the config's).
    """

    name = "station-perception"

    def __init__(
        self,
        frames: NewestSlot[Frame],
        out: NewestSlot[Perception],
        get_calibration: Callable[[], Any],
        config: Any,
        rate_hz: float,
        arm_model: Any = None,
        get_check_calibration: Callable[[], Any] | None = None,
        on_check: Callable[[Any, float | None, str | None, Perception], None] | None = None,
        get_color_model: Callable[[], Any] | None = None,
    ) -> None:
        super().__init__()
        self.get_check_calibration = get_check_calibration or get_calibration
        self.on_check = on_check
        self.get_color_model = get_color_model
        self.frames = frames
        self.out = out
        self.get_calibration = get_calibration
        self.config = config
        self.arm_model = arm_model
        self.period_s = 1.0 / rate_hz

    def _run(self) -> None:
        pipeline = PerceptionPipeline(self.config, self.arm_model)  # holds its detectors; tracks tags near calibrated spots
        drift = DriftMonitor(self.config.calibration)  # the camera-moved check of the calibration in use
        version, surface, surface_time = 0, None, None
        while not self._stop.is_set():
            frame, version = self.frames.wait_newer(version, timeout_s=0.5)
            if frame is None:
                continue
            started = time.monotonic()
            calibration = self.get_calibration()
            if self.get_color_model is not None:
                pipeline.color_model = self.get_color_model()  # the station's colour calibration, at once
            perception = analyse_frame(pipeline, frame, calibration, surface, surface_time)
            checked = self.get_check_calibration()
            warning = drift.update(frame.timestamp_s, list(perception.tags), checked, self.config)
            if warning is not None:
                perception = replace(perception, camera_warning=warning)
            if drift.checked_now and self.on_check is not None:
                try:
                    self.on_check(checked, drift.last_drift_px, warning, perception)
                except Exception:  # noqa: BLE001 - the station's reaction failing must not stop perception
                    log.exception("the camera-moved check's handler failed")
            surface, surface_time = perception.surface_depth_mm, perception.surface_time_s
            self.out.publish(perception)
            # At most the configured rate, and at most half of one core (sleep at least as long as we worked).
            elapsed = time.monotonic() - started
            self._stop.wait(max(self.period_s - elapsed, elapsed))


def analyse_frame(pipeline: Any, frame: Frame, calibration: Any, surface_depth_mm: np.ndarray | None = None,
                  surface_time_s: np.ndarray | None = None) -> Perception:
    """Tags and (with a calibration and depth) blocks of one frame, each block stamped with the
    frame's time and arm joints; the robot is filtered out when the frame carries the arm's joints
    and the pipeline has an arm model (with a held block's volume unless the gripper was open).
    surface_depth_mm, surface_time_s: the previous Perception's, updated with this frame's depth off the robot.
    A failed pass logs and reports none."""
    joints = frame.arm_joints_rad
    filter_joints = joints if getattr(pipeline, "self_filter", None) is not None else None
    held_block_edge_m = 0.0 if frame.gripper_closed is False else None  # None: the config's held block
    robot_mask = None
    try:
        result = pipeline.process(
            frame.color_bgr, frame.depth_mm, calibration, layers=None, arm_joints_rad=filter_joints,
            held_block_edge_m=held_block_edge_m, frame_time_s=frame.timestamp_s,
        )
        tags, blocks, robot_mask = tuple(result.tags), tuple(result.blocks), result.robot_mask
        if joints is not None and filter_joints is None:  # no arm model: unfiltered, but say what pose they were seen in
            seen = tuple(float(v) for v in np.ravel(joints))
            blocks = tuple(replace(block, seen_arm_joints_rad=seen) for block in blocks)
    except ValueError as error:
        log.debug("perception failed on frame %d: %s", frame.sequence, error)
        tags, blocks = (), ()
    return Perception(
        blocks=blocks, tags=tags, frame_sequence=frame.sequence, capture_time_s=frame.timestamp_s,
        arm_joints_rad=None if joints is None else tuple(float(v) for v in np.ravel(joints)), robot_mask=robot_mask,
        surface_depth_mm=surface_off_robot(frame.depth_mm, robot_mask, surface_depth_mm),
        surface_time_s=surface_times(frame.depth_mm, robot_mask, surface_time_s, frame.timestamp_s),
    )


def surface_off_robot(depth_mm: np.ndarray | None, robot_mask: np.ndarray | None, previous_mm: np.ndarray | None) -> np.ndarray | None:
    """This frame's depth where the robot is not, the previous surface (or 0: unseen) where it is;
    None without depth. Without a robot mask the frame's depth stands as it is."""
    if depth_mm is None:
        return None
    surface = np.array(depth_mm, dtype=np.uint16, copy=True)
    if robot_mask is not None and robot_mask.shape == surface.shape:
        usable = previous_mm is not None and previous_mm.shape == surface.shape
        surface[robot_mask] = previous_mm[robot_mask] if usable else 0
    return surface


def surface_times(depth_mm: np.ndarray | None, robot_mask: np.ndarray | None, previous_s: np.ndarray | None,
                  capture_time_s: float) -> np.ndarray | None:
    """When each pixel of surface_off_robot's image was seen: this frame's capture time off the robot, the
    previous time (0: never) under it."""
    if depth_mm is None:
        return None
    times = np.full(np.shape(depth_mm), float(capture_time_s))
    if robot_mask is not None and robot_mask.shape == times.shape:
        usable = previous_s is not None and previous_s.shape == times.shape
        times[robot_mask] = previous_s[robot_mask] if usable else 0.0
    return times
