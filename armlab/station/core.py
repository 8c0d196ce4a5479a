"""The Station, the gate: state table, lock, devices, job runner, e-stop; the only writer of arm commands.

Every command is checked against the transition table (states.py) under one lock and every state change
goes through `_transition`, so an e-stop and a command can never interleave: after estop() returns, no
job or manual command can reach the arm until reset(). Skills and tasks (armlab.skills, armlab.tasks)
sit above the gate and use its small public interface: `start_job`, `run_trajectory`, `run_gripper`,
`fresh_frame`, `fresh_perception`, `joints_rad`, `checked_joints`, `held_block`, `moved_over_since`.
The camera, perception and telemetry each run on their own thread (perception.py, telemetry.py), except
in synchronous mode (a fast-mode simulation for evaluations), where frames are captured on demand and
physics advances only while the gate waits for the devices.
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
from armlab.station.perception import FrameSource, Perception, PerceptionLoop, analyse_frame
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import JOB_STATES, State, allowed_commands, after_event, next_state
from armlab.station.telemetry import TelemetryPublisher, block_to_dict, gripper_pose_from_matrix
from armlab.store import Store, Waypoint

log = logging.getLogger(__name__)


class NotCalibrated(RuntimeError):
    """The command needs a camera calibration: run calibrate first."""

    def __init__(self, what: str = "this command") -> None:
        super().__init__(f"{what} needs a camera calibration: calibrate first")


# Errors that mean a device failed (→ fault), as opposed to a refused or impossible request.
DEVICE_ERRORS = (ConnectionError, TimeoutError, OSError)

WAIT_CHUNK_S = 0.05  # waits on the devices check cancel/e-stop this often (simulated time in fast mode)
MOTION_MEMORY = 256  # how many recent arm motions the gate remembers for stale-perception checks


class Station:
    """The control station's gate. Backends are injected; `sim` is the SimWorkcell when simulated (else None).

    model: the armlab.kinematics ArmModel of the arm; perception_config: armlab.vision's config.
    synchronous: the sim runs in fast mode and nothing runs on threads (evaluations); frames are
    captured when a skill asks for one and physics advances only while the gate waits.
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
        synchronous: bool = False,
    ) -> None:
        if synchronous and (sim is None or sim.realtime):
            raise ValueError("synchronous mode needs a fast-mode simulation (SimWorkcell with realtime=False)")
        self.arm, self.gripper, self.camera = arm, gripper, camera
        self.model = model
        self.config = config or StationConfig()
        self.store = store or Store(self.config.database_file())
        self.perception_config = perception_config
        self._motion_config = motion_config
        self.sim = sim
        self.backend = backend
        self.synchronous = synchronous
        self._lock = threading.RLock()
        self._state = State.IDLE
        self._detail = ""
        self._job: Job | None = None
        self._last_job: Job | None = None
        self._teach: list[Waypoint] = []
        self._calibration: Any = None
        self._calibration_info: dict | None = None
        self._controller: str | None = None
        self._held_block: dict | None = None
        self._motions: list[tuple[float, np.ndarray]] = []  # (end time_s, xy box [xmin, ymin, xmax, ymax])
        self._pipeline: Any = None  # synchronous mode's perception pipeline
        self.events = EventLog()
        self.frames: NewestSlot[Frame] = NewestSlot()
        self.perception: NewestSlot[Perception] = NewestSlot()
        self.telemetry: NewestSlot[dict] = NewestSlot()
        self.calibration_slot: NewestSlot[dict] = NewestSlot()
        self._workers: list = []
        self._started = False

    # Lifecycle ------------------------------------------------------------------------------------

    def start(self) -> None:
        """Connect devices not yet connected and start the camera, perception and telemetry threads
        (none in synchronous mode)."""
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
        if not self.synchronous:
            self._workers = [
                FrameSource(self.camera, self.frames, self.arm, self.gripper),
                PerceptionLoop(
                    self.frames, self.perception, lambda: self._calibration, self.perception_config, self.config.perception_rate_hz, self.model
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

    def _transition(self, trigger: str, *, source: str | None = None, detail: str | None = None, event: bool = False) -> State:
        """The one place the state changes. `trigger` is an operator command (checked against the table:
        CommandRefused if not allowed) or, with event=True, an internal event (job_ended, device_failed).
        Caller holds the lock. detail None keeps the detail unless the new state is idle."""
        new_state = after_event(self._state, trigger) if event else next_state(self._state, trigger)
        if source is not None:
            self._controller = source
        if new_state is not self._state or detail is not None:
            self._detail = detail if detail is not None else ("" if new_state is State.IDLE else self._detail)
        self._state = new_state
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

    @property
    def motion_config(self) -> Any:
        """armlab.motion's MotionConfig (config/motion.yaml unless one was injected)."""
        if self._motion_config is None:
            from armlab.motion.config import load_motion_config

            self._motion_config = load_motion_config()
        return self._motion_config

    @property
    def held_block(self) -> dict | None:
        """What the last pick put in the gripper (block wire dict + "height_m"), or None."""
        with self._lock:
            return None if self._held_block is None else dict(self._held_block)

    def set_held_block(self, block: dict | None) -> None:
        with self._lock:
            self._held_block = None if block is None else dict(block)

    # Status ---------------------------------------------------------------------------------------

    def joints_rad(self) -> np.ndarray:
        """The measured joint positions (rad)."""
        return np.asarray(self.arm.read_joint_state().position_rad, dtype=float)

    def checked_joints(self, q_rad) -> np.ndarray:
        """A finite joint vector inside the limits (ValueError naming the joint otherwise)."""
        return checked_joints(self.model, q_rad)

    def clock_s(self) -> float:
        """The motion clock: simulated time on the simulation, else monotonic wall time."""
        return self.sim.sim_time_s if self.sim is not None else time.monotonic()

    def status(self) -> dict:
        """GET /api/status: the wire dict (SI units)."""
        q = self.joints_rad()
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
        for block in data:
            block.setdefault("seen_time_s", perception.capture_time_s)
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
            self._transition("estop", source=source, detail="e-stop pressed: reset to continue")
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
            self._transition("reset", source=source, detail="")
        self.events.add("info", "reset: station idle")

    def cancel_job(self, source: str | None = None) -> Job:
        """Cancel the running job: the arm halts where it is, the station returns to idle.

        A job that registered a cleanup (e.g. put a held block down) runs it on its own thread after the
        cancel; the station stays in the job's state until that ends."""
        with self._lock:
            next_state(self._state, "cancel")
            job = self._job
            assert job is not None, "a job state without a job"
            job.cancel()
            self._halt_arm()
            if not job.has_cleanup:
                self._transition("cancel", source=source, detail="")
            elif source is not None:
                self._controller = source
        self.events.add("warn", f"job '{job.name}' cancelled")
        return job

    def _halt_arm(self) -> None:
        try:
            self.arm.stop()
        except DEVICE_ERRORS as error:
            log.warning("arm.stop failed: %s", error)

    # Waiting on the devices -----------------------------------------------------------------------

    def _wait_until(self, predicate: Callable[[], bool], timeout_s: float, ctx: JobContext | None = None) -> bool:
        """Block until predicate() holds (False after timeout_s of motion-clock time). On the simulation
        this lets fast mode advance the physics; a job's cancel is checked every WAIT_CHUNK_S."""
        deadline = self.clock_s() + timeout_s
        while True:
            if ctx is not None:
                ctx.check()
            if self.sim is not None:
                if self.sim.wait_for(predicate, WAIT_CHUNK_S):
                    return True
            elif predicate():
                return True
            else:
                time.sleep(0.005)
            if self.clock_s() > deadline:
                return predicate()

    def wait_motion(self, timeout_s: float) -> bool:
        """Block until the arm stops; False on timeout."""
        return self._wait_until(lambda: not self.arm.is_moving(), timeout_s)

    def wait_gripper(self, ctx: JobContext | None = None) -> None:
        """Wait until the fingers stop moving (≤ gripper_settle_timeout_s of motion-clock time)."""
        still = {"width": None, "since": self.clock_s()}

        def fingers_still() -> bool:
            width, now = self.gripper.read_state().width_m, self.clock_s()
            if still["width"] is None or abs(width - still["width"]) > 2e-4:
                still["width"], still["since"] = width, now
                return False
            return now - still["since"] > 0.15

        self._wait_until(fingers_still, self.config.gripper_settle_timeout_s, ctx)

    # Manual commands ------------------------------------------------------------------------------

    def plan_move(self, q_goal_rad, moving_time_s: float | None = None) -> JointTrajectory:
        """A checked joint move from the current position (ValueError/UnsafeTrajectory: nothing moves)."""
        from armlab.motion import check_trajectory, plan_joint_move

        q_goal = self.checked_joints(q_goal_rad)
        trajectory = plan_joint_move(
            self.joints_rad(), q_goal, self.model, moving_time_s=checked_moving_time(moving_time_s, self.config.max_moving_time_s)
        )
        check_trajectory(self.model, trajectory)
        return trajectory

    def _manual_move(self, command: str, q_goal_rad, moving_time_s: float | None, wait: bool, source: str | None) -> None:
        with self._lock:
            self._transition(command, source=source)  # state unchanged: idle/teach stay
            trajectory = self.plan_move(q_goal_rad, moving_time_s)
            self._command_arm(trajectory, self._swept_box(trajectory))
        if wait:
            self.wait_motion(trajectory.duration_s + 5.0)

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
        return self.model.ik(position, pitch=pitch_rad, yaw=yaw_rad, q_seed=self.joints_rad())

    def move_to(self, position_m, pitch_rad=None, yaw_rad=None, moving_time_s=None, wait=False, source=None) -> np.ndarray:
        """Move the gripper point to a world position (IK, joint move); returns the goal joints."""
        with self._lock:
            self.allowed_or_raise("move_to")
            q_goal = self.solve_pose(position_m, pitch_rad, yaw_rad)
            self._manual_move("move_to", q_goal, moving_time_s, wait=False, source=source)
        if wait:
            self.wait_motion(self.config.max_moving_time_s + 5.0)
        return q_goal

    def set_torque(self, enabled: bool, source: str | None = None) -> None:
        with self._lock:
            self._transition("torque", source=source)
            self.arm.set_torque(bool(enabled))
        self.events.add("info", f"torque {'on' if enabled else 'off'}")

    def gripper_command(self, action: str, wait: bool = True, source: str | None = None) -> None:
        """'grasp' or 'release'."""
        if action not in ("grasp", "release"):
            raise ValueError(f"gripper action must be 'grasp' or 'release', not {action!r}")
        with self._lock:
            self._transition("gripper", source=source)
            getattr(self.gripper, action)(wait=False)
        if wait:
            self.wait_gripper()

    # Teach ----------------------------------------------------------------------------------------

    def teach_start(self, source: str | None = None) -> None:
        with self._lock:
            self._transition("teach_start", source=source, detail="teaching: 0 waypoints")
            self._teach = []
        self.events.add("info", "teach mode: record waypoints, then stop with a name")

    def teach_record(self, source: str | None = None) -> Waypoint:
        """Add the current joints and gripper command as a waypoint."""
        with self._lock:
            next_state(self._state, "teach_record")
            q = self.joints_rad()
            command = self.gripper.read_state().command
            waypoint = Waypoint(tuple(float(v) for v in q), command if command in ("grasp", "release") else "release")
            self._teach.append(waypoint)
            self._transition("teach_record", source=source, detail=f"teaching: {len(self._teach)} waypoints")
        return waypoint

    def teach_stop(self, name: str, source: str | None = None):
        """Save the recorded waypoints as a program and return to idle (Program)."""
        with self._lock:
            next_state(self._state, "teach_stop")
            program = self.store.save_program(name, self._teach)
            self._transition("teach_stop", source=source, detail="")
            self._teach = []
        self.events.add("info", f"program '{program.name}' saved ({len(program.waypoints)} waypoints)")
        return program

    # Jobs -----------------------------------------------------------------------------------------

    def current_job(self) -> Job | None:
        with self._lock:
            return self._job or self._last_job

    def start_job(
        self,
        command: str,
        name: str,
        function: Callable[[JobContext], Any],
        detail: str = "",
        source=None,
        cleanup: Callable[[JobContext], Any] | None = None,
    ) -> Job:
        """Enter the job's state and run function(ctx) on a job thread (CommandRefused if not allowed).

        cleanup(ctx), if given, runs after a cancel (not after an e-stop) with the arm still the job's,
        e.g. to put a held block down; the station returns to idle when it ends."""
        with self._lock:
            next_state(self._state, command)
            if command not in ("calibrate", "grab", "drop", "repeat", "auto"):
                raise ValueError(f"'{command}' does not start a job")
            job = Job(name=name, detail=detail, has_cleanup=cleanup is not None)
            self._transition(command, source=source, detail=detail or name)
            self._job = job
            start_job_thread(job, function, self._on_job_end, cleanup=cleanup)
        self.events.add("info", f"job '{name}' started" + (f": {detail}" if detail else ""))
        return job

    def _on_job_end(self, job: Job, error: BaseException | None) -> None:
        with self._lock:
            if self._job is job:
                self._job, self._last_job = None, job
                if self._state in JOB_STATES:
                    event = "device_failed" if isinstance(error, DEVICE_ERRORS) else "job_ended"
                    if self._transition(event, event=True) is State.FAULT:
                        self._detail = f"device failure in job '{job.name}': {error}"
                        self._halt_arm()
        try:
            self.store.record_job(job.to_dict())
        except Exception as store_error:  # noqa: BLE001 - the job's outcome matters more than its record
            log.warning("could not record job %s: %s", job.id, store_error)
        level = {"succeeded": "info", "cancelled": "warn"}.get(job.state, "error")
        self.events.add(level, f"job '{job.name}' {job.state}: {job.message}")

    def _owns_arm(self, ctx: JobContext) -> None:
        """Inside a job, under the lock: JobCancelled unless this job may still command the devices
        (it is current and not cancelled, or it is running its cleanup after a cancel)."""
        if self._job is not ctx.job or self._state not in JOB_STATES:
            raise JobCancelled("job is no longer current")
        if not ctx.in_cleanup:
            ctx.check()

    def _swept_box(self, trajectory: JointTrajectory) -> np.ndarray:
        """[xmin, ymin, xmax, ymax] of the gripper point along a trajectory (sampled; no lock needed)."""
        positions = trajectory.positions_rad
        tips = self.model.fk(positions[:: max(1, len(positions) // 20)])[:, :2, 3]
        tips = np.vstack([tips, self.model.fk(positions[-1])[:2, 3]])
        return np.concatenate([tips.min(axis=0), tips.max(axis=0)])

    def _command_arm(self, trajectory: JointTrajectory, swept_box: np.ndarray) -> None:
        """Send a checked trajectory and remember where the gripper sweeps (caller holds the lock)."""
        self.arm.command_trajectory(trajectory)
        self._motions.append((time.time() + trajectory.duration_s, swept_box))
        del self._motions[:-MOTION_MEMORY]

    def moved_over_since(self, point_m, since_s: float, radius_m: float = 0.06) -> bool:
        """True if a motion that ended after `since_s` (wall time, like frame timestamps) swept the gripper
        within radius_m of point_m in x-y: a detection seen at since_s may be stale there."""
        x, y = float(point_m[0]), float(point_m[1])
        with self._lock:
            motions = list(self._motions)
        for end_s, (xmin, ymin, xmax, ymax) in motions:
            if end_s > since_s and xmin - radius_m <= x <= xmax + radius_m and ymin - radius_m <= y <= ymax + radius_m:
                return True
        return False

    def run_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: command a trajectory (only while this job owns the arm) and wait for it."""
        swept_box = self._swept_box(trajectory)
        with self._lock:
            self._owns_arm(ctx)
            self._command_arm(trajectory, swept_box)
        checked = ctx if not ctx.in_cleanup else None
        if not self._wait_until(lambda: not self.arm.is_moving(), trajectory.duration_s + 5.0, checked):
            self._halt_arm()
            raise TimeoutError(f"the arm did not finish a {trajectory.duration_s:.2f} s move in time")
        with self._lock:
            self._motions[-1] = (time.time(), self._motions[-1][1])
        if checked is not None:
            ctx.check()

    def run_gripper(self, ctx: JobContext, action: str) -> None:
        """Inside a job: grasp or release (only while this job owns the arm) and wait for the fingers."""
        if action not in ("grasp", "release"):
            raise ValueError(f"gripper action must be 'grasp' or 'release', not {action!r}")
        with self._lock:
            self._owns_arm(ctx)
            getattr(self.gripper, action)(wait=False)
        self.wait_gripper(ctx if not ctx.in_cleanup else None)

    def move_in_job(self, ctx: JobContext, q_goal_rad, moving_time_s: float | None = None) -> None:
        self.run_trajectory(ctx, self.plan_move(q_goal_rad, moving_time_s))

    # Perception for skills ------------------------------------------------------------------------

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

    def fresh_perception(self, ctx: JobContext | None = None, timeout_s: float = 5.0) -> Perception:
        """Perception of a frame captured after this call began (so after the last motion ended).

        Synchronous mode: captured and analysed now. Otherwise: waits for the perception thread."""
        if self.synchronous:
            from armlab.vision.pipeline import PerceptionPipeline

            if self._pipeline is None:
                self._pipeline = PerceptionPipeline(self.perception_config, arm_model=self.model)
            frame = self.fresh_frame()
            perception = analyse_frame(self._pipeline, frame, self.calibration)
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
