"""What the gate sees and reports: its status (GET /api/status), detections (marked stale while the camera is
lost), telemetry snapshots and fresh frames and perception for skills.

A mixin of core.Station.
"""

from __future__ import annotations

import time

import numpy as np

from armlab.devices.camera import Frame
from armlab.station.jobs import JobContext
from armlab.station.perception import DEVICE_ERRORS, Perception, analyse_frame
from armlab.station.states import allowed_commands
from armlab.station.telemetry import block_to_dict, gripper_pose_from_matrix
from armlab.vision.pipeline import PerceptionPipeline


class Perceiving:
    """Status, detections, telemetry snapshots, fresh frames and perception."""

    def detections(self) -> dict:
        """GET /api/detections: the newest detected blocks as wire dicts; none, with stale: true and the
        reason, while the camera is lost or perception is older than camera_timeout_s."""
        perception, _ = self.perception.get()
        if perception is None:
            return {"data": [], "count": 0, "time_s": time.time(), "frame_sequence": -1, "stale": False, "stale_reason": None}
        stale_reason = self._perception_stale_reason(perception)
        data = [] if stale_reason else [block_to_dict(index, block) for index, block in enumerate(perception.blocks)]
        for block in data:
            block.setdefault("seen_time_s", perception.capture_time_s)
        return {
            "data": data, "count": len(data), "time_s": perception.time_s, "frame_sequence": perception.frame_sequence,
            "stale": stale_reason is not None, "stale_reason": stale_reason,
        }

    def _perception_stale_reason(self, perception: Perception) -> str | None:
        camera_lost = self.latch.lost().get("camera")
        if camera_lost is not None:
            return f"the camera is lost ({camera_lost})"
        age_s = time.time() - perception.capture_time_s
        if not self.synchronous and age_s > self.config.camera_timeout_s:
            return f"the newest perception is {age_s:.1f} s old"
        return None

    def _gripper_pose_matrix(self, q_read: np.ndarray) -> np.ndarray:
        """The gripper's pose from joint readings: the calibrated arm's (fk_measured) when there is one."""
        fk_measured = getattr(self.model, "fk_measured", None)
        return fk_measured(q_read) if fk_measured is not None else self.model.fk(q_read)

    def status(self) -> dict:
        """GET /api/status: the wire dict (SI units). Works with a device lost (its last reading is shown)."""
        moving_measured, gripper_dict = False, {"width_m": 0.0, "holding": False, "command": "release"}
        try:
            joint_state = self.arm.read_joint_state()
            q = np.asarray(joint_state.position_rad, dtype=float)
            self._last_joints = q
            speed = np.abs(np.asarray(joint_state.velocity_rad_s, dtype=float))
            moving_measured = bool(self.arm.is_moving()) or bool(speed.size and speed.max() > self.config.moving_speed_rad_s)
        except DEVICE_ERRORS:
            q = self._last_joints if self._last_joints is not None else np.asarray(self.model.home_rad if self.has_arm else [], dtype=float)
        try:
            gripper = self.gripper.read_state()
            gripper_dict = {"width_m": float(gripper.width_m), "holding": bool(gripper.holding), "command": gripper.command}
        except DEVICE_ERRORS:
            pass
        with self._lock:
            job = self._job or self._last_job
            state, detail, lease = self._effective_state(), self._detail, self._lease.to_dict()
        lost = self.latch.lost()
        calibrated, checked = self.trust.calibration is not None, self.trust.checked
        perception, _ = self.perception.get()
        camera_warning = perception.camera_warning if checked and perception is not None else None
        commanded = self.commanded_joints_rad() if self.has_arm else None
        return {
            "state": state.value,
            "detail": detail,
            "joints_rad": [float(v) for v in q],
            "commanded_joints_rad": None if commanded is None else [float(v) for v in commanded],
            "joint_names": list(self.model.joint_names) if self.has_arm else [],
            "joint_limits_rad": [[float(lo), float(hi)] for lo, hi in zip(self.model.lower_rad, self.model.upper_rad)] if self.has_arm else [],
            "gripper": gripper_dict,
            "gripper_pose": gripper_pose_from_matrix(self._gripper_pose_matrix(q), np.asarray(self.model.T_world_base)[:3, 3]) if self.has_arm else None,
            "moving": moving_measured,
            "torque_enabled": self._torque_enabled,
            "calibrated": calibrated,
            "camera_warning": camera_warning,
            "calibration_state": self.calibration_state,
            "arm_calibration": self.arm_calibration_status if self.has_arm else None,
            "self_recalibrate": self.self_recalibrate,
            "backend": self.backend,
            "controller": lease["controller"],
            "controller_since_s": lease["since_s"],
            "devices_lost": lost,
            "speed_percent": self.speed_percent,
            "job": job.to_dict() if job is not None else None,
            "allowed_commands": allowed_commands(state, self.has_arm),
            "time_s": time.time(),
        }

    def telemetry_snapshot(self) -> dict:
        """Status + detections: one telemetry message (the TelemetryPublisher calls this)."""
        snapshot = self.status()
        detections = self.detections()
        snapshot["detections"] = detections["data"]
        snapshot["detections_stale"] = detections["stale"]
        return snapshot


    def fresh_frame(self, timeout_s: float = 2.0, max_age_s: float = 2.0) -> Frame:
        """A camera frame taken now (synchronous mode: rendered now; else the newest, waiting for a newer
        one when it is older than max_age_s). TimeoutError (a device error) when the camera gives none."""
        if self.synchronous:
            frame = self.sim.capture_next_frame()
            self.frames.publish(frame)
            return frame
        frame, version = self.frames.get()
        if frame is None or time.time() - frame.timestamp_s > max_age_s:
            frame, _ = self.frames.wait_newer(version, timeout_s)
        if frame is None or time.time() - frame.timestamp_s > max_age_s + timeout_s:
            raise TimeoutError(f"no fresh camera frame within {timeout_s} s: is the camera running?")
        return frame

    def frame_after(self, since_s: float, timeout_s: float = 3.0) -> Frame:
        """The first camera frame whose picture was taken at or after wall time since_s (synchronous mode:
        rendered now). What a command that follows a change (a scene, the arm's arrival, a request) must
        look at: the newest frame may show the world a second ago, more on a busy machine. TimeoutError
        when the camera gives none in timeout_s."""
        if self.synchronous:
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

        Synchronous mode: captured and analysed now. Otherwise: waits for the perception thread."""
        if self.synchronous:
            if self._pipeline is None:
                self._pipeline = PerceptionPipeline(self.perception_config, arm_model=self.model)
            self._pipeline.color_model = self.colors.model
            frame = self.fresh_frame()
            previous, _ = self.perception.get()
            perception = analyse_frame(self._pipeline, frame, self.calibration, previous.surface_depth_mm if previous else None,
                                      previous.surface_time_s if previous else None)
            self.perception.publish(perception)
            return perception
        asked_s = time.time()
        deadline = time.monotonic() + timeout_s
        _, version = self.perception.get()
        while time.monotonic() < deadline:
            if ctx is not None:
                ctx.check()
            perception, version = self.perception.wait_newer(version, timeout_s=0.2)
            if perception is not None and perception.capture_time_s >= asked_s:
                return perception
        raise TimeoutError(f"no perception of a fresh frame within {timeout_s} s: is the camera running?")
