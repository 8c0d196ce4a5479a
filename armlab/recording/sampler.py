"""Sampling the station into StationChannels, on two threads of the recorder's own (never the station's).

- the sample loop (joint_rate_hz): measured and commanded joints every tick (a recording's, batch_joints, kept as
  readings and built, encoded and written at the next slow tick, all together: one warm pass instead of a
  little Python on every 10 ms wake-up; the live server's at once, no added latency); every 1/transforms_rate_hz the frame
  transforms (the URDF's links included), the gripper, the state (its changes as log lines) and the job, new
  detections, the task's plan and the event log's new entries (the log's listener only appends to a bounded deque;
  nothing waits on the station's lock beyond its own short reads);
- the image loop: the newest camera frame (NewestSlot: newest value wins, a slow encoder skips frames, nothing
  queues), at most camera_rate_hz colour frames as JPEG and depth_rate_hz depth frames, with the camera's
  calibration when it changes and every CALIBRATION_PERIOD_S (a file cut short still has one near its end).

Every message's log time is time.time_ns() when it was sampled; its header timestamp is the reading's own
(the joint state's or the frame's capture time). `housekeeping()` (the recorder's flush, disk and budget checks) runs
on the sample loop between ticks.

A channel that says no sink wants it (a foxglove channel's has_sinks(): the live server's channels before a client
subscribes) is neither sampled nor encoded: an idle live server costs the station a wake-up per tick and per frame.
A config with sampler_niceness (the live server's) runs both threads that much nicer than the station's own (Linux's
per-thread nice): on a busy machine the simulation's and the devices' threads get the CPU first.
"""

from __future__ import annotations

import errno
import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import cv2
import numpy as np

from armlab.recording import channels as ch
from armlab.recording.scaling import scaled
from armlab.recording.urdf_frames import UrdfFrames, finger_offset_m, joint_positions, station_urdf
from armlab.station.config import SamplingConfig
from armlab.station.perception import DEVICE_ERRORS
from armlab.station.telemetry import block_to_dict

log = logging.getLogger(__name__)

CALIBRATION_PERIOD_S = 5.0
HELD_COMMAND_PERIOD_NS = 1_000_000_000  # an unchanged commanded reference is logged this often
PLAN_PERIOD_NS = 1_000_000_000  # an unchanged plan is logged this often (a client that subscribes later sees it)
EVENT_BACKLOG = 1000  # events waiting for the sample loop; older ones are dropped (and counted)


class StationSampler:
    """Samples `station` into `channels` (a StationChannels) until stop(). counts: messages logged per topic."""

    def __init__(self, station: Any, channels: ch.StationChannels, config: SamplingConfig,
                 housekeeping: Callable[[], None] | None = None, on_failure: Callable[[str], None] | None = None,
                 thread_prefix: str = "recording", batch_joints: bool = False) -> None:
        self.station, self.channels, self.config = station, channels, config
        # batch_joints: the joint readings are taken every tick but built, encoded and written at the slow tick, all
        # together (a recording's file: up to 1/transforms_rate_hz later; a live client gets them at once)
        self.batch_joints = batch_joints
        self._joint_batch: list[tuple] = []  # (attribute, topic, log time, header time, positions, velocities)
        self.thread_prefix = thread_prefix  # its threads: <prefix>-sampler, <prefix>-images
        self.housekeeping = housekeeping
        self.on_failure = on_failure  # on_failure(reason): a loop ended on an error (e.g. the disk is full)
        self.counts: dict[str, int] = dict.fromkeys(ch.TOPICS, 0)
        self.jobs: list[str] = []  # the names of the jobs seen running, in order
        self.states: list[str] = []  # the station's states seen (idle, teach, repeat, ...), first time each, in order
        self.dropped_events = 0
        self.ticks = 0  # sample-loop ticks done
        self.error: str | None = None  # the first sampling error (the loop goes on)
        self._events: deque[dict] = deque(maxlen=EVENT_BACKLOG)
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._state: str | None = None
        self._job_id: str | None = None
        self._perception_version = 0
        self._reading_ns = 0  # the newest joint reading's own time, recorded
        self._commanded: np.ndarray | None = None
        self._commanded_ns = 0
        self._link_q: np.ndarray | None = None
        self._link_poses: dict[str, np.ndarray] | None = None  # the links' world poses at _link_q
        self._calibration_key: tuple | None = None
        self._calibration_s = -float("inf")
        self._plan: Any = False  # the plan last logged (False: none yet)
        self._plan_ns = 0
        self._urdf: UrdfFrames | None = None
        self._links_key: tuple | None = None  # (q, finger offset) of _links
        self._links: list = []  # the URDF's link transforms at _links_key
        self._tf_parts: dict = {}  # channels.frame_transform's cache: unchanged transforms are not converted again

    # Lifecycle ------------------------------------------------------------------------------------

    def start(self) -> None:
        self.station.events.add_listener(self._on_event)
        self._threads = [threading.Thread(target=self._guarded, args=(self._sample_loop,), name=f"{self.thread_prefix}-sampler", daemon=True)]
        if self.config.camera_rate_hz > 0 or self.config.depth_rate_hz > 0:
            self._threads.append(threading.Thread(target=self._guarded, args=(self._image_loop,), name=f"{self.thread_prefix}-images", daemon=True))
        for thread in self._threads:
            if not self._stop.is_set():  # the sample loop may stop the recording at once (its first flush: disk, budget)
                thread.start()

    def stop(self, timeout_s: float = 5.0) -> bool:
        """Stop both loops (from any thread, one of the loops included); True if every other loop ended."""
        self._stop.set()
        self.station.events.remove_listener(self._on_event)
        deadline = time.monotonic() + timeout_s
        ended = True
        for thread in self._threads:
            if thread is not threading.current_thread() and thread.ident is not None:  # started
                thread.join(max(0.0, deadline - time.monotonic()))
                ended = ended and not thread.is_alive()
        return ended

    def _guarded(self, loop: Callable[[], None]) -> None:
        niceness = int(getattr(self.config, "sampler_niceness", 0))
        if niceness > 0 and hasattr(os, "setpriority"):  # Linux: a thread's own nice value (its native id)
            try:
                tid = threading.get_native_id()
                os.setpriority(os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + niceness))
            except OSError as error:
                log.warning("%s: cannot lower its priority: %s", threading.current_thread().name, error)
        try:
            loop()
        except Exception as error:  # noqa: BLE001 - a recording bug must never reach the station
            log.exception("recording loop %s failed", threading.current_thread().name)
            self.error = self.error or f"{type(error).__name__}: {error}"
            if self.on_failure is not None and not self._stop.is_set():
                self.on_failure(f"{'disk full' if isinstance(error, OSError) and error.errno == errno.ENOSPC else 'writing failed'}: "
                                f"{type(error).__name__}: {error}")

    def _log(self, topic: str, channel: Any, message: Any, time_ns: int) -> None:
        channel.log(message, log_time=time_ns)
        self.counts[topic] += 1

    @staticmethod
    def _wanted(channel: Any) -> bool:
        """False when the channel says no sink takes its messages (then they are not even built)."""
        has_sinks = getattr(channel, "has_sinks", None)
        return has_sinks is None or bool(has_sinks())

    def _on_event(self, event: dict) -> None:  # on the publishing thread: append only
        if len(self._events) == self._events.maxlen:
            self.dropped_events += 1
        self._events.append(event)

    # The sample loop --------------------------------------------------------------------------------

    def _sample_loop(self) -> None:
        period_s = 1.0 / self.config.joint_rate_hz
        slow_every = max(1, round(self.config.joint_rate_hz / self.config.transforms_rate_hz))
        tick, next_s = 0, time.monotonic()
        while not self._stop.is_set():
            q = self._joints()
            if tick % slow_every == 0:
                self._write_joints()
                self._slow(q)
                if self.housekeeping is not None:
                    self.housekeeping()
            tick += 1
            self.ticks = tick
            next_s += period_s
            delay = next_s - time.monotonic()
            if delay < -period_s:  # far behind (a busy machine): do not burst to catch up
                next_s, delay = time.monotonic(), 0.0
            self._stop.wait(max(0.0, delay))
        self._write_joints()  # the readings of the last ticks: a stopped recording keeps them

    def _joints(self) -> np.ndarray | None:
        station = self.station
        if not station.has_arm:
            return None
        try:
            reading = station.arm.read_joint_state()
        except DEVICE_ERRORS:
            return None
        now_ns, reading_ns = time.time_ns(), ch.seconds_to_ns(reading.timestamp_s)
        if reading_ns > self._reading_ns and self._wanted(self.channels.joint_states):  # a driver publishing slower than
            self._reading_ns = reading_ns  # joint_rate_hz repeats its last reading: logged once
            self._joint_message("joint_states", "/joint_states", now_ns, reading_ns, reading.position_rad, reading.velocity_rad_s)
        commanded = station.commanded_joints_rad() if self._wanted(self.channels.joint_commands) else None
        if commanded is not None and (self._commanded is None or not np.array_equal(commanded, self._commanded)
                                      or now_ns - self._commanded_ns >= HELD_COMMAND_PERIOD_NS):
            self._commanded, self._commanded_ns = commanded, now_ns  # a held command: once a second, not at 100 Hz
            self._joint_message("joint_commands", "/joint_commands", now_ns, now_ns, commanded, None)
        return np.asarray(reading.position_rad, dtype=float)

    def _joint_message(self, attribute: str, topic: str, now_ns: int, stamp_ns: int, positions, velocities) -> None:
        """A JointStates message of the station's joints, logged now or, with batch_joints, at the next slow tick."""
        if self.batch_joints:  # copies: a driver may reuse its arrays before the slow tick
            self._joint_batch.append((attribute, topic, now_ns, stamp_ns, np.array(positions, dtype=float),
                                      None if velocities is None else np.array(velocities, dtype=float)))
        else:
            self._log(topic, getattr(self.channels, attribute),
                      ch.joint_states(stamp_ns, self.station.model.joint_names, positions, velocities), now_ns)

    def _write_joints(self) -> None:
        """The batched joint messages, in the order they were sampled (each with its own log time)."""
        if not self._joint_batch:
            return
        batch, self._joint_batch = self._joint_batch, []
        names = self.station.model.joint_names
        for attribute, topic, now_ns, stamp_ns, positions, velocities in batch:
            self._log(topic, getattr(self.channels, attribute), ch.joint_states(stamp_ns, names, positions, velocities), now_ns)

    def _slow(self, q: np.ndarray | None) -> None:
        """Transforms, gripper, state and job, detections, plan, events."""
        now_ns = time.time_ns()
        gripper = None
        if self._wanted(self.channels.gripper) or self._wanted(self.channels.tf):
            try:
                gripper = self.station.gripper.read_state()
            except DEVICE_ERRORS:
                pass
        if self._wanted(self.channels.tf):
            self._transforms(q, gripper, now_ns)
        if gripper is not None and self._wanted(self.channels.gripper):
            self._log("/gripper", self.channels.gripper, {"time_s": now_ns / 1e9, "width_m": float(gripper.width_m),
                                                          "holding": bool(gripper.holding), "command": str(gripper.command)}, now_ns)
        job = self._state_and_job(now_ns)
        if self._wanted(self.channels.detections) or self._wanted(self.channels.detections_scene):
            self._detections(now_ns)
        if self._wanted(self.channels.plan):
            self._log_plan(job, now_ns)
        self.log_events(now_ns)

    def _transforms(self, q: np.ndarray | None, gripper: Any, now_ns: int) -> None:
        """world -> base, the joints, the gripper point and the camera; the URDF's links from their parents."""
        station = self.station
        poses: dict[str, np.ndarray] = {}
        links: list = []
        if station.has_arm:
            poses["base"] = np.asarray(station.model.T_world_base)
            if q is not None:
                if self._link_poses is None or not np.array_equal(q, self._link_q):  # the arm at rest: computed once
                    frames = station.model.joint_frames(q)
                    self._link_q, self._link_poses = q, {
                        **{name: frame for name, frame in zip(station.model.joint_names, frames[:-1])}, "gripper": frames[-1]}
                poses.update(self._link_poses)
                if self._urdf is None:
                    self._urdf = UrdfFrames(station_urdf(station))
                finger = finger_offset_m(station, float(gripper.width_m)) if gripper is not None else None
                key = (q.tobytes(), finger)
                if key != self._links_key:  # the arm and the gripper at rest: computed once
                    self._links_key = key
                    self._links = [link for link in self._urdf.transforms(joint_positions(station.model.joint_names, q, finger))
                                   if not (link[0] == "world" and link[1] in poses)]  # world -> base: once
                links = self._links
        calibration = station.calibration
        if calibration is not None:
            poses["camera"] = np.asarray(calibration.T_world_camera)
        if poses or links:
            self._log("/tf", self.channels.tf, ch.frame_transforms(now_ns, poses, links, self._tf_parts), now_ns)

    def log_events(self, now_ns: int) -> None:
        """The event log's new entries (also called once more after the loops stop: the last ones are kept)."""
        wanted = self._wanted(self.channels.events)
        while self._events:
            event = self._events.popleft()
            if not wanted:
                continue
            event_ns = ch.seconds_to_ns(event["time_s"])
            self._log("/events", self.channels.events, ch.log_message(event_ns, event["level"], event["message"]), max(now_ns, event_ns))

    def _state_and_job(self, now_ns: int) -> Any:
        """The state's changes as log lines (name "state"; the jobs' starts and ends are in the event log); returns
        the current job."""
        state = self.station.state.value
        if state != self._state:
            previous, self._state = self._state, state
            if state not in self.states:
                self.states.append(state)
            text = f"state: {state}" if previous is None else f"state: {previous} -> {state}"
            if self._wanted(self.channels.events):
                self._log("/events", self.channels.events, ch.log_message(now_ns, "info", text, "state"), now_ns)
        job = self.station.current_job()
        if job is not None and job.id != self._job_id and job.state == "running":
            self._job_id = job.id
            self.jobs.append(job.name)
        return job

    def _log_plan(self, job: Any, now_ns: int) -> None:
        """The running task's next move (its progress's next_block and next_target_m), when it changes and every
        PLAN_PERIOD_NS; none: the plan deleted."""
        task = job.extra.get("task") if job is not None and job.state == "running" and isinstance(job.extra, dict) else None
        plan = {"next_block": task.get("next_block"), "next_target_m": task.get("next_target_m")} if isinstance(task, dict) else None
        if plan is not None and plan["next_block"] is None:
            plan = None
        if plan != self._plan or now_ns - self._plan_ns >= PLAN_PERIOD_NS:
            self._plan, self._plan_ns = plan, now_ns
            self._log("/plan", self.channels.plan, ch.plan_scene(now_ns, plan), now_ns)

    def _detections(self, now_ns: int) -> None:
        perception, version = self.station.perception.get()
        if perception is None or version == self._perception_version:
            return
        self._perception_version = version
        blocks = [block_to_dict(index, block) for index, block in enumerate(perception.blocks)]
        self._log("/detections", self.channels.detections,
                  {"time_s": float(perception.capture_time_s), "frame_sequence": int(perception.frame_sequence), "blocks": blocks}, now_ns)
        self._log("/detections/scene", self.channels.detections_scene, ch.detections_scene(now_ns, blocks), now_ns)

    # The image loop ---------------------------------------------------------------------------------

    def _image_loop(self) -> None:
        color_period_s = 1.0 / self.config.camera_rate_hz if self.config.camera_rate_hz > 0 else None
        depth_period_s = 1.0 / self.config.depth_rate_hz if self.config.depth_rate_hz > 0 else None
        next_color_s = next_depth_s = 0.0
        quality = [int(cv2.IMWRITE_JPEG_QUALITY), int(self.config.jpeg_quality)]
        _, version = self.station.frames.get()
        version -= 1  # the frame already there counts as new
        while not self._stop.is_set():
            frame, newer = self.station.frames.wait_newer(version, 0.2)
            if newer == version:
                continue
            version = newer  # even with no frame yet (version 0): the next wait then waits
            if frame is None:
                continue
            if self.config.image_delay_s > 0 and self._stop.wait(self.config.image_delay_s):
                break  # after the stream's and perception's work on this frame (SamplingConfig.image_delay_s)
            now_s, now_ns = time.monotonic(), time.time_ns()
            frame_ns = ch.seconds_to_ns(frame.timestamp_s)
            if color_period_s is not None and now_s >= next_color_s and self._wanted(self.channels.color):
                next_color_s = max(next_color_s + color_period_s, now_s - color_period_s)
                ok, jpeg = cv2.imencode(".jpg", self._scaled(frame.color_bgr, cv2.INTER_AREA), quality)
                if ok:
                    self._calibration(frame, frame_ns, now_ns)
                    self._log("/camera/color/compressed", self.channels.color, ch.compressed_image(frame_ns, jpeg.tobytes()), now_ns)
            if depth_period_s is not None and frame.depth_mm is not None and now_s >= next_depth_s and self._wanted(self.channels.depth):
                next_depth_s = max(next_depth_s + depth_period_s, now_s - depth_period_s)
                self._calibration(frame, frame_ns, now_ns)
                self._log("/camera/depth", self.channels.depth, ch.depth_image(frame_ns, self._scaled(frame.depth_mm, cv2.INTER_NEAREST)), now_ns)

    def _scaled(self, image: np.ndarray, interpolation: int) -> np.ndarray:
        """camera_scale of the image (depth: nearest, so every value is one the camera measured), on this thread
        (scaling.py: the same pixels as cv2.resize without OpenCV's thread pool)."""
        return scaled(image, self.config.camera_scale, interpolation)

    def _calibration(self, frame: Any, frame_ns: int, now_ns: int) -> None:
        if not self._wanted(self.channels.calibration):
            return
        try:
            intrinsics = self.station.intrinsics.current()  # measured for this camera, else the device's own
        except DEVICE_ERRORS:
            intrinsics = frame.intrinsics
        if intrinsics is None:
            return
        key = (intrinsics.width, intrinsics.height, intrinsics.fx, intrinsics.fy, intrinsics.cx, intrinsics.cy, tuple(intrinsics.dist))
        now_s = time.monotonic()
        if key != self._calibration_key or now_s - self._calibration_s >= CALIBRATION_PERIOD_S:
            self._calibration_key, self._calibration_s = key, now_s
            scaled = ch.scaled_intrinsics(intrinsics, self.config.camera_scale)
            self._log("/camera/calibration", self.channels.calibration, ch.camera_calibration(frame_ns, scaled), now_ns)
