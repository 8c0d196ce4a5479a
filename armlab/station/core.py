"""The Station: owns the devices, the calibration and the running job; the only writer of arm commands.

Every command is checked against the transition table (states.py) under one lock, so an e-stop and a
command can never interleave: after estop() returns, no job or manual command can reach the arm until
reset(). Long actions (calibrate, grab, drop, repeat, tasks) run as cancellable jobs (jobs.py); the
camera, perception and telemetry each run on their own thread (perception.py, telemetry.py).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from armlab.devices.arm import Arm, JointTrajectory
from armlab.devices.camera import Camera, Frame
from armlab.devices.gripper import Gripper
from armlab.station.checks import checked_joints, checked_moving_time, checked_position
from armlab.station.config import StationConfig
from armlab.station.jobs import Job, JobCancelled, JobContext, start_job_thread
from armlab.station.perception import FrameSource, Perception, PerceptionLoop
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import State, allowed_commands, after_event, next_state
from armlab.station.telemetry import TelemetryPublisher, block_to_dict, gripper_pose_from_matrix
from armlab.store import Store, Waypoint

log = logging.getLogger(__name__)


class NotCalibrated(RuntimeError):
    """The command needs a camera calibration: run calibrate first."""

    def __init__(self, what: str = "this command") -> None:
        super().__init__(f"{what} needs a camera calibration: calibrate first")


# Errors that mean a device failed (→ fault), as opposed to a refused or impossible request.
DEVICE_ERRORS = (ConnectionError, TimeoutError, OSError)


class Station:
    """The control station. Backends are injected; `sim` is the SimWorkcell when simulated (else None).

    model: the armlab.kinematics ArmModel of the arm; perception_config: armlab.vision's config.
    """

    def __init__(
        self,
        arm: Arm,
        gripper: Gripper,
        camera: Camera,
        *,
        model: Any,
        config: StationConfig | None = None,
        store: Store | None = None,
        perception_config: Any = None,
        motion_config: Any = None,
        sim: Any = None,
        backend: str = "sim",
    ) -> None:
        self.arm, self.gripper, self.camera = arm, gripper, camera
        self.model = model
        self.config = config or StationConfig()
        self.store = store or Store(self.config.database_file())
        self.perception_config = perception_config
        self.motion_config = motion_config
        self.sim = sim
        self.backend = backend
        self._lock = threading.RLock()
        self._state = State.IDLE
        self._detail = ""
        self._job: Job | None = None
        self._last_job: Job | None = None
        self._teach: list[Waypoint] = []
        self._calibration: Any = None
        self._calibration_info: dict | None = None
        self._controller: str | None = None
        self.held_block: dict | None = None  # what the last grab picked (wire dict + "height_m")
        self.events = EventLog()
        self.frames: NewestSlot[Frame] = NewestSlot()
        self.perception: NewestSlot[Perception] = NewestSlot()
        self.telemetry: NewestSlot[dict] = NewestSlot()
        self.calibration_slot: NewestSlot[dict] = NewestSlot()
        self._workers: list = []
        self._started = False

    # Lifecycle ------------------------------------------------------------------------------------

    def start(self) -> None:
        """Connect devices not yet connected and start the camera, perception and telemetry threads."""
        if self._started:
            return
        for device in (self.arm, self.gripper, self.camera):
            if not device.is_connected:
                device.connect()
        if self.perception_config is None:
            from armlab.vision import load_perception_config

            self.perception_config = load_perception_config()
        if self.config.restore_calibration:
            self._restore_calibration()
        self._workers = [
            FrameSource(self.camera, self.frames),
            PerceptionLoop(
                self.frames, self.perception, lambda: self._calibration, self.perception_config, self.config.perception_rate_hz
            ),
            TelemetryPublisher(self.telemetry_snapshot, self.telemetry, self.config.telemetry_rate_hz),
        ]
        for worker in self._workers:
            worker.start()
        self._started = True
        self.events.add("info", f"station started ({self.backend})")

    def close(self) -> None:
        """Stop the job and the threads, halt the arm. The devices (or the sim) are closed by their owner."""
        with self._lock:
            if self._job is not None:
                self._job.cancel()
            try:
                self.arm.stop()
            except DEVICE_ERRORS:
                pass
        for worker in reversed(self._workers):
            worker.stop()
        self._workers = []
        self._started = False

    @property
    def is_running(self) -> bool:
        """True between start() and close() (the camera, perception and telemetry threads run)."""
        return self._started

    # State ----------------------------------------------------------------------------------------

    @property
    def state(self) -> State:
        with self._lock:
            return self._state

    def allowed_commands(self) -> list[str]:
        with self._lock:
            return allowed_commands(self._state)

    def allowed_or_raise(self, command: str) -> None:
        """CommandRefused (naming the allowed commands) unless `command` is allowed right now."""
        with self._lock:
            next_state(self._state, command)

    def _accept(self, command: str, source: str | None) -> State:
        """Check `command` against the table (CommandRefused if not allowed); return the next state.

        Caller holds the lock and assigns the state once its own checks passed.
        """
        new_state = next_state(self._state, command)
        if source is not None:
            self._controller = source
        return new_state

    @property
    def calibration(self) -> Any:
        with self._lock:
            return self._calibration

    @property
    def calibration_info(self) -> dict:
        with self._lock:
            return dict(self._calibration_info) if self._calibration_info else {"calibrated": False}

    def set_calibration(self, calibration: Any, info: dict) -> None:
        """Install a calibration (armlab.vision Calibration) with its wire summary; publishes it."""
        with self._lock:
            self._calibration = calibration
            self._calibration_info = {"calibrated": True, **info}
        self.calibration_slot.publish(self.calibration_info)

    def _restore_calibration(self) -> None:
        from armlab.vision import Calibration

        data = self.store.latest_calibration()
        if data is None:
            return
        try:
            calibration = Calibration.from_dict(data["calibration"])
        except (KeyError, ValueError, TypeError) as error:
            self.events.add("warn", f"saved calibration not restored: {error}")
            return
        self.set_calibration(calibration, data["info"])

    # Status ---------------------------------------------------------------------------------------

    def status(self) -> dict:
        """GET /api/status: the wire dict (SI units)."""
        joint_state = self.arm.read_joint_state()
        q = np.asarray(joint_state.position_rad, dtype=float)
        gripper = self.gripper.read_state()
        with self._lock:
            job = self._job or self._last_job
            state, detail, controller = self._state, self._detail, self._controller
            calibrated = self._calibration is not None
        return {
            "state": state.value,
            "detail": detail,
            "joints_rad": [float(v) for v in q],
            "joint_names": list(self.model.joint_names),
            "joint_limits_rad": [[float(lo), float(hi)] for lo, hi in zip(self.model.lower_rad, self.model.upper_rad)],
            "gripper": {"width_m": float(gripper.width_m), "holding": bool(gripper.holding), "command": gripper.command},
            "gripper_pose": gripper_pose_from_matrix(self.model.fk(q)),
            "moving": bool(self.arm.is_moving()),
            "calibrated": calibrated,
            "backend": self.backend,
            "controller": controller,
            "job": job.to_dict() if job is not None else None,
            "allowed_commands": allowed_commands(state),
            "time_s": time.time(),
        }

    def detections(self) -> dict:
        """GET /api/detections: the newest detected blocks as wire dicts."""
        perception, _ = self.perception.get()
        if perception is None:
            return {"data": [], "count": 0, "time_s": time.time(), "frame_sequence": -1}
        data = [block_to_dict(index, block) for index, block in enumerate(perception.blocks)]
        return {"data": data, "count": len(data), "time_s": perception.time_s, "frame_sequence": perception.frame_sequence}

    def telemetry_snapshot(self) -> dict:
        """Status + detections: one telemetry message (the TelemetryPublisher calls this)."""
        snapshot = self.status()
        snapshot["detections"] = self.detections()["data"]
        return snapshot

    # Safety ---------------------------------------------------------------------------------------

    def estop(self, source: str | None = None) -> None:
        """Halt now and latch: cancel the job, stop arm and gripper. Allowed in every state."""
        with self._lock:
            self._state = self._accept("estop", source)
            self._detail = "e-stop pressed: reset to continue"
            if self._job is not None:
                self._job.cancel()
            failures = []
            for device in (self.arm, self.gripper):
                try:
                    device.stop()
                except DEVICE_ERRORS as error:  # still latched: the state refuses every motion
                    failures.append(f"{device}: {error}")
        self.events.add("error", "E-stop: motion halted" + (f" ({'; '.join(failures)})" if failures else ""))

    def reset(self, source: str | None = None) -> None:
        """Leave estop/fault for idle without moving the arm."""
        with self._lock:
            self._state = self._accept("reset", source)
            self._detail = ""
        self.events.add("info", "reset: station idle")

    def cancel_job(self, source: str | None = None) -> Job:
        """Cancel the running job: the arm halts where it is, the station returns to idle."""
        with self._lock:
            new_state = self._accept("cancel", source)
            job = self._job
            assert job is not None, "a job state without a job"
            job.cancel()
            self._halt_arm()
            self._state, self._detail = new_state, ""
        self.events.add("warn", f"job '{job.name}' cancelled")
        return job

    def _halt_arm(self) -> None:
        try:
            self.arm.stop()
        except DEVICE_ERRORS as error:
            log.warning("arm.stop failed: %s", error)

    # Manual commands ------------------------------------------------------------------------------

    def _checked_joints(self, q_rad) -> np.ndarray:
        return checked_joints(self.model, q_rad)

    def plan_move(self, q_goal_rad, moving_time_s: float | None = None) -> JointTrajectory:
        """A checked joint move from the current position (ValueError/UnsafeTrajectory: nothing moves)."""
        from armlab.motion import check_trajectory, plan_joint_move

        q_goal = self._checked_joints(q_goal_rad)
        q_now = np.asarray(self.arm.read_joint_state().position_rad, dtype=float)
        trajectory = plan_joint_move(q_now, q_goal, self.model, moving_time_s=checked_moving_time(moving_time_s, self.config.max_moving_time_s))
        check_trajectory(self.model, trajectory)
        return trajectory

    def _manual_move(self, command: str, q_goal_rad, moving_time_s: float | None, wait: bool, source: str | None) -> None:
        with self._lock:
            self._accept(command, source)  # state unchanged: idle/teach stay
            trajectory = self.plan_move(q_goal_rad, moving_time_s)
            self.arm.command_trajectory(trajectory)
        if wait:
            self.wait_motion(trajectory.duration_s + 5.0)

    def wait_motion(self, timeout_s: float) -> bool:
        """Block until the arm stops (or the station is e-stopped); False on timeout."""
        deadline = time.monotonic() + timeout_s
        while self.arm.is_moving():
            if time.monotonic() > deadline:
                return False
            time.sleep(0.01)
        return True

    def move_joints(self, q_rad, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._manual_move("move_joints", q_rad, moving_time_s, wait, source)

    def home(self, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._manual_move("home", self.model.home_rad, moving_time_s, wait, source)

    def sleep(self, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._manual_move("sleep", self.model.sleep_rad, moving_time_s, wait, source)

    def solve_pose(self, position_m, pitch_rad: float | None = None, yaw_rad: float | None = None) -> np.ndarray:
        """IK for a world position (Unreachable, a ValueError, says why); validates the numbers first."""
        position = checked_position(position_m)
        for name, angle in (("pitch_rad", pitch_rad), ("yaw_rad", yaw_rad)):
            if angle is not None and not math.isfinite(float(angle)):
                raise ValueError(f"{name} must be finite")
        q_seed = np.asarray(self.arm.read_joint_state().position_rad, dtype=float)
        return self.model.ik(position, pitch=pitch_rad, yaw=yaw_rad, q_seed=q_seed)

    def move_to(self, position_m, pitch_rad=None, yaw_rad=None, moving_time_s=None, wait=False, source=None) -> np.ndarray:
        """Move the gripper point to a world position (IK, joint move); returns the goal joints."""
        with self._lock:
            self._accept("move_to", source)
            q_goal = self.solve_pose(position_m, pitch_rad, yaw_rad)
            self._manual_move("move_to", q_goal, moving_time_s, wait=False, source=None)
        if wait:
            self.wait_motion(self.config.max_moving_time_s + 5.0)
        return q_goal

    def set_torque(self, enabled: bool, source: str | None = None) -> None:
        with self._lock:
            self._accept("torque", source)
            self.arm.set_torque(bool(enabled))
        self.events.add("info", f"torque {'on' if enabled else 'off'}")

    def gripper_command(self, action: str, wait: bool = True, source: str | None = None) -> None:
        """'grasp' or 'release'."""
        if action not in ("grasp", "release"):
            raise ValueError(f"gripper action must be 'grasp' or 'release', not {action!r}")
        with self._lock:
            self._accept("gripper", source)
            getattr(self.gripper, action)(wait=False)
        if wait:
            self.wait_gripper()

    def wait_gripper(self, ctx: JobContext | None = None) -> None:
        """Poll until the fingers stop moving (≤ gripper_settle_timeout_s)."""
        deadline = time.monotonic() + self.config.gripper_settle_timeout_s
        last_width, still_since = None, time.monotonic()
        while time.monotonic() < deadline:
            if ctx is not None:
                ctx.check()
            width = self.gripper.read_state().width_m
            if last_width is None or abs(width - last_width) > 2e-4:
                last_width, still_since = width, time.monotonic()
            elif time.monotonic() - still_since > 0.15:
                return
            time.sleep(0.02)

    # Teach and repeat -----------------------------------------------------------------------------

    def teach_start(self, source: str | None = None) -> None:
        with self._lock:
            self._state = self._accept("teach_start", source)
            self._detail = "teaching: 0 waypoints"
            self._teach = []
        self.events.add("info", "teach mode: record waypoints, then stop with a name")

    def teach_record(self, source: str | None = None) -> Waypoint:
        """Add the current joints and gripper command as a waypoint."""
        with self._lock:
            self._accept("teach_record", source)
            q = self.arm.read_joint_state().position_rad
            command = self.gripper.read_state().command
            waypoint = Waypoint(tuple(float(v) for v in q), command if command in ("grasp", "release") else "release")
            self._teach.append(waypoint)
            self._detail = f"teaching: {len(self._teach)} waypoints"
        return waypoint

    def teach_stop(self, name: str, source: str | None = None):
        """Save the recorded waypoints as a program and return to idle (Program)."""
        with self._lock:
            new_state = self._accept("teach_stop", source)
            program = self.store.save_program(name, self._teach)
            self._state, self._detail, self._teach = new_state, "", []
        self.events.add("info", f"program '{program.name}' saved ({len(program.waypoints)} waypoints)")
        return program

    # Jobs -----------------------------------------------------------------------------------------

    def current_job(self) -> Job | None:
        with self._lock:
            return self._job or self._last_job

    def start_job(self, command: str, name: str, function: Callable[[JobContext], Any], detail: str = "", source=None) -> Job:
        """Enter the job's state and run function(ctx) on a job thread (CommandRefused if not allowed)."""
        with self._lock:
            new_state = self._accept(command, source)
            job = Job(name=name, detail=detail)
            self._state, self._detail, self._job = new_state, detail or name, job
            start_job_thread(job, function, self._on_job_end)
        self.events.add("info", f"job '{name}' started" + (f": {detail}" if detail else ""))
        return job

    def _on_job_end(self, job: Job, error: BaseException | None) -> None:
        with self._lock:
            if self._job is job:
                self._job, self._last_job = None, job
                event = "device_failed" if isinstance(error, DEVICE_ERRORS) else "job_ended"
                self._state = after_event(self._state, event)
                if self._state is State.IDLE:
                    self._detail = ""
                elif self._state is State.FAULT:
                    self._detail = f"device failure in job '{job.name}': {error}"
                    self._halt_arm()
        try:
            self.store.record_job(job.to_dict())
        except Exception as store_error:  # noqa: BLE001 - the job's outcome matters more than its record
            log.warning("could not record job %s: %s", job.id, store_error)
        level = {"succeeded": "info", "cancelled": "warn"}.get(job.state, "error")
        self.events.add(level, f"job '{job.name}' {job.state}: {job.message}")

    def run_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: command a trajectory (only while this job is current) and wait for it."""
        with self._lock:
            ctx.check()
            if self._job is not ctx.job:
                raise JobCancelled("job is no longer current")
            self.arm.command_trajectory(trajectory)
        deadline = time.monotonic() + trajectory.duration_s + 5.0
        while self.arm.is_moving():
            ctx.check()
            if time.monotonic() > deadline:
                self._halt_arm()
                raise TimeoutError(f"the arm did not finish a {trajectory.duration_s:.2f} s move in time")
            time.sleep(0.01)
        ctx.check()

    def run_gripper(self, ctx: JobContext, action: str) -> None:
        """Inside a job: grasp or release (only while this job is current) and wait for the fingers."""
        with self._lock:
            ctx.check()
            if self._job is not ctx.job:
                raise JobCancelled("job is no longer current")
            getattr(self.gripper, action)(wait=False)
        self.wait_gripper(ctx)

    def move_in_job(self, ctx: JobContext, q_goal_rad, moving_time_s: float | None = None) -> None:
        self.run_trajectory(ctx, self.plan_move(q_goal_rad, moving_time_s))

    # Long actions (armlab.station.actions) ----------------------------------------------------------

    def calibrate(self, source: str | None = None) -> Job:
        from armlab.station import actions

        return actions.calibrate(self, source=source)

    def grab(self, position_m=None, pixel=None, source: str | None = None) -> Job:
        from armlab.station import actions

        return actions.grab(self, position_m=position_m, pixel=pixel, source=source)

    def drop(self, position_m=None, pixel=None, source: str | None = None) -> Job:
        from armlab.station import actions

        return actions.drop(self, position_m=position_m, pixel=pixel, source=source)

    def repeat(self, program_id: int, cycles: int = 1, source: str | None = None) -> Job:
        from armlab.station import actions

        return actions.repeat(self, program_id, cycles, source=source)

    def pixel_to_world(self, u: float, v: float) -> dict:
        from armlab.station import actions

        return actions.pixel_to_world(self, u, v)
