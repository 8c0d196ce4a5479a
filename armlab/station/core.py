"""The Station, the gate: state table, lock, latch, lease, devices, job runner, e-stop; the only writer of arm commands.

Every command is checked against the transition table (states.py) and the control lease (lease.py) under
one lock, and every state change goes through `_transition`. The lock guards state only: it is never
held across I/O (SQLite, IK, planning, scene changes). E-stop does not take it first: it sets a lock-free
latch (`_halt`), cancels the job and halts the arm and gripper, and only then records the state; every
command path checks the latch under the lock before it reaches a device, and every wait checks it, so
after estop() returns no job or manual command can reach the arm until reset(). A lost device (watch.py)
latches the same way and puts the station in `fault`; reset is refused while it is still gone.
Skills and tasks (armlab.skills, armlab.tasks) sit above the gate and use its small public interface:
`start_job`, `run_trajectory`, `run_gripper`, `fresh_frame`, `fresh_perception`, `joints_rad`,
`checked_joints`, `held_block`/`set_held_block`, `moved_over_since`, `clock_s`. The camera, perception,
telemetry and device watch each run on their own thread, except in synchronous mode (a fast-mode
simulation for evaluations), where frames are captured on demand and physics advances only while the
gate waits for the devices.
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
from armlab.errors import CommandRefused, DeviceLost, NeedsConfirmation, ShuttingDown
from armlab.station.checks import checked_joints, checked_moving_time, checked_position
from armlab.station.config import StationConfig
from armlab.station.jobs import Job, JobCancelled, JobContext, start_job_thread
from armlab.station.lease import ControlLease
from armlab.station.perception import DEVICE_ERRORS, FrameSource, Perception, PerceptionLoop, analyse_frame
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import JOB_STATES, State, after_event, allowed_commands, next_state
from armlab.station.telemetry import TelemetryPublisher, block_to_dict, gripper_pose_from_matrix
from armlab.station.watch import DeviceWatch
from armlab.store import Store, Waypoint

log = logging.getLogger(__name__)

__all__ = ["DEVICE_ERRORS", "NotCalibrated", "Station"]


class NotCalibrated(RuntimeError):
    """The command needs a camera calibration: run calibrate first."""

    def __init__(self, what: str = "this command") -> None:
        super().__init__(f"{what} needs a camera calibration: calibrate first")


WAIT_CHUNK_S = 0.05  # waits on the devices check cancel/e-stop this often (simulated time in fast mode)
MOTION_MEMORY = 256  # how many recent arm motions the gate remembers for stale-perception checks
_UNLATCHED = ("estop",)  # the only command the latch and the lease never refuse


class Station:
    """The control station's gate. Backends are injected; `sim` is the SimWorkcell when simulated (else None).

    model: the armlab.kinematics ArmModel of the arm; perception_config: armlab.vision's config.
    synchronous: the sim runs in fast mode and nothing runs on threads (evaluations); frames are
    captured when a skill asks for one and physics advances only while the gate waits.
    `source` (every command): the controller's name for the lease (None: an in-process caller, not leased).
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
        self._halt = threading.Event()  # the latch: set by e-stop and device loss (before any lock), cleared by reset
        self._closing = threading.Event()
        self._state = State.IDLE
        self._detail = ""
        self._lease = ControlLease()
        self._job: Job | None = None
        self._last_job: Job | None = None
        self._teach: list[Waypoint] = []
        self._teach_saving = False
        self._jog: dict | None = None  # the running jog: trajectory, start clock, velocity, controller
        self._calibration: Any = None
        self._calibration_info: dict | None = None
        self._held_block: dict | None = None
        self._lost: dict[str, str] = {}  # devices not answering: {name: reason}
        self._last_joints: np.ndarray | None = None
        self._motions: list[tuple[float, np.ndarray]] = []  # (end time_s, xy box [xmin, ymin, xmax, ymax])
        self._pipeline: Any = None  # synchronous mode's perception pipeline
        self.events = EventLog()
        self.frames: NewestSlot[Frame] = NewestSlot()
        self.perception: NewestSlot[Perception] = NewestSlot()
        self.telemetry: NewestSlot[dict] = NewestSlot()
        self.calibration_slot: NewestSlot[dict] = NewestSlot()
        self._workers: list = []
        self._frame_source: FrameSource | None = None
        self._started = False

    # Lifecycle ------------------------------------------------------------------------------------

    def start(self) -> None:
        """Connect devices not yet connected and start the camera, perception, telemetry and device-watch
        threads (none in synchronous mode)."""
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
        self._closing.clear()
        if not self.synchronous:
            self._frame_source = FrameSource(self.camera, self.frames, self.arm, self.gripper)
            self._workers = [
                self._frame_source,
                PerceptionLoop(
                    self.frames, self.perception, lambda: self._calibration, self.perception_config, self.config.perception_rate_hz, self.model
                ),
                TelemetryPublisher(self.telemetry_snapshot, self.telemetry, self.config.telemetry_rate_hz),
                DeviceWatch(self.device_problems, self._on_device_problems, 1.0 / self.config.device_check_rate_hz),
            ]
        for worker in self._workers:
            worker.start()
        self._started = True
        self.events.add("info", f"station started ({self.backend})")

    def begin_shutdown(self) -> None:
        """Refuse new commands, cancel the job and halt the arm and gripper, at once (a signal handler may
        call this): waiting requests then return promptly. close() finishes the job."""
        self._closing.set()
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel()
        self._halt_devices()

    def close(self) -> dict:
        """Stop the job and the threads (each join bounded by close_timeout_s), halt the arm.

        Returns {"joined": [thread names], "alive": [names still running]} and logs it; the devices (or
        the sim) are closed by their owner."""
        self.begin_shutdown()
        deadline = time.monotonic() + self.config.close_timeout_s
        joined, alive = [], []
        job = self._job
        if job is not None and job.thread is not None:
            job.thread.join(max(0.0, deadline - time.monotonic()))
            (alive if job.thread.is_alive() else joined).append(job.thread.name)
        for worker in self._workers:
            worker.request_stop()
        for worker in reversed(self._workers):
            ended = worker.stop(max(0.05, deadline - time.monotonic()))
            (joined if ended else alive).append(worker.name)
        self._workers = []
        self._started = False
        report = {"joined": joined, "alive": alive}
        if alive:
            log.warning("station closed; threads still running: %s (joined: %s)", ", ".join(alive), ", ".join(joined) or "none")
        else:
            log.info("station closed; threads joined: %s", ", ".join(joined) or "none")
        return report

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
            return allowed_commands(self._effective_state())

    def allowed_or_raise(self, command: str, source: str | None = None) -> None:
        """CommandRefused (naming the allowed commands) unless `command` is allowed right now;
        NotController if `source` may not command (the lease is not taken by this check)."""
        with self._lock:
            self._check(command, source)

    def _effective_state(self) -> State:
        """The state, or estop while the latch is set ahead of the transition (caller holds the lock)."""
        if self._halt.is_set() and self._state not in (State.ESTOP, State.FAULT):
            return State.ESTOP
        return self._state

    def _check(self, command: str, source: str | None) -> State:
        """Refusals of an operator command, in order: shutting down, the latch/state table, the lease.
        Returns the state it would lead to. Caller holds the lock."""
        if self._closing.is_set() and command not in _UNLATCHED:
            raise ShuttingDown(f"command '{command}' refused: the station is shutting down")
        new_state = next_state(self._effective_state(), command)
        if command not in _UNLATCHED and source is not None and self._lease.holder not in (None, source):
            self._lease.require(source, command)  # raises NotController naming the holder
        return new_state

    def _transition(self, trigger: str, *, source: str | None = None, detail: str | None = None, event: bool = False) -> State:
        """The one place the state changes. `trigger` is an operator command (checked against the table,
        the latch and the lease: CommandRefused/NotController; a free lease goes to `source`) or, with
        event=True, an internal event (job_ended, device_failed). Caller holds the lock. detail None
        keeps the detail unless the new state is idle."""
        if event:
            new_state = after_event(self._state, trigger)
        else:
            new_state = self._check(trigger, source)
            if trigger not in _UNLATCHED and self._lease.require(source, trigger):
                self.events.add("info", f"control taken by '{source}' (the lease was free)")
        if new_state is not self._state or detail is not None:
            self._detail = detail if detail is not None else ("" if new_state is State.IDLE else self._detail)
        self._state = new_state
        return new_state

    # Control lease --------------------------------------------------------------------------------

    @property
    def controller(self) -> str | None:
        """Who holds the control lease (None: free)."""
        with self._lock:
            return self._lease.holder

    def take_control(self, source: str) -> str | None:
        """Take the control lease over (explicitly); the event log tells everyone, the previous holder too.
        Returns the previous holder."""
        if self._closing.is_set():
            raise ShuttingDown("the station is shutting down")
        with self._lock:
            previous = self._lease.take(source)
        if previous != source:
            taken_from = f" from '{previous}'" if previous else ""
            self.events.add("warn", f"control taken by '{source}'{taken_from}")
        return previous

    def release_control(self, source: str, reason: str = "released") -> bool:
        """Give the lease up if `source` holds it (reason: e.g. 'disconnected'); True if it did."""
        with self._lock:
            released = self._lease.release(source)
            if released and self._jog is not None and self._jog["source"] == source:
                self._jog = None
        if released:
            self.events.add("info", f"control {reason}: '{source}' no longer controls the station")
        return released

    # Calibration and configuration ----------------------------------------------------------------

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

    def set_scene(self, scene: Any, source: str | None = None) -> None:
        """Simulation: replace the objects (armlab.scene Scene). Checked (state, lease) under the lock; the
        scene change itself runs outside it, so an e-stop never waits for it."""
        if self.sim is None:
            raise ValueError("set_scene needs the simulation backend")
        with self._lock:
            self._transition("set_scene", source=source)
        self.sim.set_scene(scene)
        self.set_held_block(None)

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
        """GET /api/status: the wire dict (SI units). Works with a device lost (its last reading is shown)."""
        moving_measured, gripper_dict = False, {"width_m": 0.0, "holding": False, "command": "release"}
        try:
            joint_state = self.arm.read_joint_state()
            q = np.asarray(joint_state.position_rad, dtype=float)
            self._last_joints = q
            speed = np.abs(np.asarray(joint_state.velocity_rad_s, dtype=float))
            moving_measured = bool(self.arm.is_moving()) or bool(speed.size and speed.max() > self.config.moving_speed_rad_s)
        except DEVICE_ERRORS:
            q = self._last_joints if self._last_joints is not None else np.asarray(self.model.home_rad, dtype=float)
        try:
            gripper = self.gripper.read_state()
            gripper_dict = {"width_m": float(gripper.width_m), "holding": bool(gripper.holding), "command": gripper.command}
        except DEVICE_ERRORS:
            pass
        with self._lock:
            job = self._job or self._last_job
            state, detail, lease = self._effective_state(), self._detail, self._lease.to_dict()
            calibrated = self._calibration is not None
            lost = dict(self._lost)
        return {
            "state": state.value,
            "detail": detail,
            "joints_rad": [float(v) for v in q],
            "joint_names": list(self.model.joint_names),
            "joint_limits_rad": [[float(lo), float(hi)] for lo, hi in zip(self.model.lower_rad, self.model.upper_rad)],
            "gripper": gripper_dict,
            "gripper_pose": gripper_pose_from_matrix(self.model.fk(q)),
            "moving": moving_measured,
            "calibrated": calibrated,
            "backend": self.backend,
            "controller": lease["controller"],
            "controller_since_s": lease["since_s"],
            "devices_lost": lost,
            "job": job.to_dict() if job is not None else None,
            "allowed_commands": allowed_commands(state),
            "time_s": time.time(),
        }

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
        with self._lock:
            camera_lost = self._lost.get("camera")
        if camera_lost is not None:
            return f"the camera is lost ({camera_lost})"
        age_s = time.time() - perception.capture_time_s
        if not self.synchronous and age_s > self.config.camera_timeout_s:
            return f"the newest perception is {age_s:.1f} s old"
        return None

    def telemetry_snapshot(self) -> dict:
        """Status + detections: one telemetry message (the TelemetryPublisher calls this)."""
        snapshot = self.status()
        detections = self.detections()
        snapshot["detections"] = detections["data"]
        snapshot["detections_stale"] = detections["stale"]
        return snapshot

    # Safety: e-stop, device loss, reset -------------------------------------------------------------

    def _halt_devices(self, gripper: bool = True) -> list[str]:
        """Stop the arm (and gripper); never raises (a lost device is reported). No lock needed."""
        failures = []
        for device in (self.arm, self.gripper) if gripper else (self.arm,):
            try:
                device.stop()
            except DEVICE_ERRORS as error:
                failures.append(f"{device}: {error}")
        return failures

    def estop(self, source: str | None = None) -> None:
        """Halt now and latch, from any state and from anyone (no lease needed): latch first, cancel the
        job, stop arm and gripper, then record the state; a command that was being sent when the latch
        went up is stopped by a second halt once the lock shows it has finished."""
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel()
        failures = self._halt_devices()
        with self._lock:
            self._jog = None
            by = f" by '{source}'" if source else ""
            self._transition("estop", source=source, detail=f"e-stop pressed{by}: reset to continue")
        failures += self._halt_devices()
        self.events.add("error", "E-stop: motion halted" + (f" ({'; '.join(sorted(set(failures)))})" if failures else ""))

    def device_problems(self) -> dict[str, str]:
        """{device: reason} for each device not answering now (reads the arm and gripper, checks the
        camera's frames); empty when all answer."""
        problems: dict[str, str] = {}
        for name, read in (("arm", self.arm.read_joint_state), ("gripper", self.gripper.read_state)):
            try:
                read()
            except DEVICE_ERRORS as error:
                problems[name] = f"{type(error).__name__}: {error}"
        if self._frame_source is not None and self._started:
            camera = self._frame_source.health(self.config.camera_timeout_s)
            if camera is not None:
                problems["camera"] = camera
        return problems

    def _on_device_problems(self, problems: dict[str, str]) -> None:
        """The device watch's report: fault on a new loss, log a recovery (the station stays in fault)."""
        with self._lock:
            new = {name: reason for name, reason in problems.items() if name not in self._lost}
            back = [name for name in self._lost if name not in problems]
            self._lost = dict(problems)
        for name in back:
            self.events.add("info", f"{name} answers again: reset to continue")
        if new:
            self.device_failed(", ".join(new), "; ".join(new.values()))

    def device_failed(self, device: str, reason: str) -> None:
        """A device is lost: latch, cancel the job, hold the arm still, enter fault with the reason."""
        self._halt.set()
        job = self._job
        if job is not None:
            job.cancel()
        self._halt_devices()
        with self._lock:
            self._jog = None
            if self._transition("device_failed", event=True) is State.FAULT:
                self._detail = f"{device} lost: {reason}; reset once it is back"
        self.events.add("error", f"{device} lost: {reason}: motion halted")

    def reset(self, source: str | None = None) -> None:
        """Leave estop/fault for idle without moving the arm; DeviceLost while a device is still gone."""
        with self._lock:
            if self._state not in (State.ESTOP, State.FAULT):  # not while an e-stop is still being recorded
                raise CommandRefused("reset", self._effective_state().value, allowed_commands(self._effective_state()))
            self._check("reset", source)
        problems = self.device_problems()  # device reads: outside the lock
        if problems:
            with self._lock:
                self._lost.update(problems)
            raise DeviceLost("reset refused: " + "; ".join(f"the {name} is still lost ({reason})" for name, reason in problems.items()))
        with self._lock:
            self._transition("reset", source=source, detail="")
            self._lost = {}
            self._halt.clear()
        self.events.add("info", "reset: station idle")

    def cancel_job(self, source: str | None = None) -> Job:
        """Cancel the running job: the arm halts where it is, the station returns to idle.

        A job that registered a cleanup (e.g. put a held block down) runs it on its own thread after the
        cancel; the station stays in the job's state until that ends."""
        with self._lock:
            self._check("cancel", source)
            job = self._job
            assert job is not None, "a job state without a job"
            job.cancel()  # under the lock: any command the job is sending has finished or will see it
            if not job.has_cleanup:
                self._transition("cancel", source=source, detail="")
        self._halt_devices(gripper=False)
        self.events.add("warn", f"job '{job.name}' cancelled")
        return job

    # Waiting on the devices -----------------------------------------------------------------------

    def _wait_until(self, predicate: Callable[[], bool], timeout_s: float, ctx: JobContext | None = None) -> bool:
        """Block until predicate() holds (False after timeout_s of motion-clock time, or at once when the
        latch is set). On the simulation this lets fast mode advance the physics, never beyond one
        control period after the latch; a job's cancel is checked every WAIT_CHUNK_S."""
        deadline = self.clock_s() + timeout_s
        latched = self._halt.is_set
        while True:
            if ctx is not None:
                ctx.check()
            if latched():
                if ctx is not None and not ctx.in_cleanup:
                    raise JobCancelled("the station was e-stopped")
                return predicate()
            if self.sim is not None:
                if self.sim.wait_for(lambda: predicate() or latched(), WAIT_CHUNK_S) and not latched():
                    return True
            elif predicate():
                return True
            else:
                self._halt.wait(0.005)
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

    # Sending motion: every trajectory from any source passes here ----------------------------------

    def check_motion(self, trajectory: JointTrajectory) -> None:
        """The full safety check of a trajectory (UnsafeTrajectory says why): joint, velocity and
        acceleration limits, the table, the workspace box, the per-step jump. No lock needed (pure)."""
        from armlab.motion import check_trajectory

        config = self.motion_config
        check_trajectory(
            self.model, trajectory, clearance_m=config.board_clearance_m, workspace_m=config.workspace_m, max_step_rad=config.max_step_rad
        )

    def _command_arm(self, trajectory: JointTrajectory, swept_box: np.ndarray) -> None:
        """Send a checked trajectory and remember where the gripper sweeps. Caller holds the lock and has
        checked the state; the latch and the start (no jump from the measured joints) are checked here."""
        from armlab.motion.safety import check_start

        if self._halt.is_set():
            raise CommandRefused("move", self._effective_state().value, allowed_commands(self._effective_state()))
        check_start(trajectory, self.joints_rad(), self.motion_config.start_tolerance_rad, self.model.joint_names)
        self.arm.command_trajectory(trajectory)
        self._motions.append((time.time() + trajectory.duration_s, swept_box))
        del self._motions[:-MOTION_MEMORY]

    def _swept_box(self, trajectory: JointTrajectory) -> np.ndarray:
        """[xmin, ymin, xmax, ymax] of the gripper point along a trajectory (sampled; no lock needed)."""
        positions = trajectory.positions_rad
        tips = self.model.fk(positions[:: max(1, len(positions) // 20)])[:, :2, 3]
        tips = np.vstack([tips, self.model.fk(positions[-1])[:2, 3]])
        return np.concatenate([tips.min(axis=0), tips.max(axis=0)])

    # Manual commands ------------------------------------------------------------------------------

    def plan_move(self, q_goal_rad, moving_time_s: float | None = None) -> JointTrajectory:
        """A checked joint move from the current position (ValueError/UnsafeTrajectory: nothing moves)."""
        from armlab.motion import plan_joint_move

        q_goal = self.checked_joints(q_goal_rad)
        trajectory = plan_joint_move(
            self.joints_rad(), q_goal, self.model, moving_time_s=checked_moving_time(moving_time_s, self.config.max_moving_time_s)
        )
        self.check_motion(trajectory)
        return trajectory

    def _manual_move(self, command: str, q_goal_rad, moving_time_s: float | None, wait: bool, source: str | None) -> None:
        self.allowed_or_raise(command, source)  # refuse before planning
        trajectory = self.plan_move(q_goal_rad, moving_time_s)  # planning and checks: outside the lock
        swept_box = self._swept_box(trajectory)
        with self._lock:
            self._transition(command, source=source)  # state unchanged: idle/teach stay
            self._jog = None
            self._command_arm(trajectory, swept_box)
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
        """Move the gripper point to a world position (IK outside the lock, joint move); returns the goal joints."""
        self.allowed_or_raise("move_to", source)
        q_goal = self.solve_pose(position_m, pitch_rad, yaw_rad)
        self._manual_move("move_to", q_goal, moving_time_s, wait=False, source=source)
        if wait:
            self.wait_motion(self.config.max_moving_time_s + 5.0)
        return q_goal

    def jog(self, velocity_rad_s, source: str | None = None) -> JointTrajectory:
        """Hold-to-run: move at these joint velocities (rad/s) for motion jog_hold_s, then stop by itself.
        Sending it again (or heartbeat()) within jog_hold_s keeps it going; zeros ramp down to rest."""
        from armlab.motion.jog import checked_jog_velocity, plan_jog, reference_velocity

        velocity = checked_jog_velocity(velocity_rad_s, self.model.velocity_limit_rad_s, self.model.joint_names)
        self.allowed_or_raise("jog", source)
        with self._lock:
            jog = dict(self._jog) if self._jog is not None else None
        q0, v0 = self.joints_rad(), np.zeros_like(velocity)
        if jog is not None and self.arm.is_moving():
            _, v0 = reference_velocity(jog["trajectory"], self.clock_s() - jog["start_s"])
        config = self.motion_config
        trajectory = plan_jog(
            q0, v0, velocity, config.jog_hold_s, self.model.lower_rad, self.model.upper_rad, self.model.accel_limit_rad_s2,
            config.sample_rate_hz,
        )
        self.check_motion(trajectory)
        swept_box = self._swept_box(trajectory)
        with self._lock:
            self._transition("jog", source=source)
            self._command_arm(trajectory, swept_box)
            self._jog = {"trajectory": trajectory, "start_s": self.clock_s(), "velocity": velocity, "source": source}
        return trajectory

    def heartbeat(self, source: str | None = None) -> bool:
        """The controlling client is still there: extend its running jog by jog_hold_s. False (nothing
        moves) when it has no jog running."""
        with self._lock:
            jog = self._jog
        if jog is None or jog["source"] != source or not self.arm.is_moving():
            return False
        self.jog(jog["velocity"], source=source)
        return True

    def set_torque(self, enabled: bool, source: str | None = None, confirm: bool = False) -> None:
        """Torque on, or off (limp: the arm falls under gravity unless held), which outside teach needs
        confirm=True (NeedsConfirmation otherwise: nothing changes)."""
        with self._lock:
            state = self._check("torque", source)
            if not enabled and state is not State.TEACH and not confirm:
                raise NeedsConfirmation(
                    "torque off outside teach lets the arm fall under gravity: hold the arm and send confirm: true "
                    "(or start teach first)"
                )
            self._transition("torque", source=source)
            self._jog = None
            if self._halt.is_set():
                raise CommandRefused("torque", self._effective_state().value, allowed_commands(self._effective_state()))
            self.arm.set_torque(bool(enabled))
        self.events.add("warn" if not enabled else "info", f"torque {'on' if enabled else 'off'}")

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
        self.allowed_or_raise("teach_record", source)
        q = self.joints_rad()
        command = self.gripper.read_state().command
        waypoint = Waypoint(tuple(float(v) for v in q), command if command in ("grasp", "release") else "release")
        with self._lock:
            if self._teach_saving:
                raise CommandRefused("teach_record", "teach (saving)", [])
            self._transition("teach_record", source=source, detail=f"teaching: {len(self._teach) + 1} waypoints")
            self._teach.append(waypoint)
        return waypoint

    def teach_stop(self, name: str, source: str | None = None):
        """Save the recorded waypoints as a program (the SQLite write runs outside the lock) and return to
        idle (Program). An e-stop during the write keeps the program and the latch."""
        with self._lock:
            self._check("teach_stop", source)
            if self._teach_saving:
                raise CommandRefused("teach_stop", "teach (saving)", [])
            self._teach_saving = True
            waypoints = list(self._teach)
        try:
            program = self.store.save_program(name, waypoints)
        finally:
            with self._lock:
                self._teach_saving = False
        with self._lock:
            self._teach = []
            if self._state is State.TEACH:
                self._transition("teach_stop", source=source, detail="")
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
            self._check(command, source)
            if command not in ("calibrate", "grab", "drop", "repeat", "auto"):
                raise ValueError(f"'{command}' does not start a job")
            job = Job(name=name, detail=detail, has_cleanup=cleanup is not None)
            self._transition(command, source=source, detail=detail or name)
            self._job = job
            self._jog = None
            start_job_thread(job, function, self._on_job_end, cleanup=cleanup)
        self.events.add("info", f"job '{name}' started" + (f": {detail}" if detail else ""))
        return job

    def _on_job_end(self, job: Job, error: BaseException | None) -> None:
        if isinstance(error, DEVICE_ERRORS) and self._job is job:
            self.device_failed(f"a device in job '{job.name}'", f"{type(error).__name__}: {error}")
        with self._lock:
            if self._job is job:
                self._job, self._last_job = None, job
                if self._state in JOB_STATES:
                    self._transition("job_ended", event=True)
        try:
            self.store.record_job(job.to_dict())
        except Exception as store_error:  # noqa: BLE001 - the job's outcome matters more than its record
            log.warning("could not record job %s: %s", job.id, store_error)
        level = {"succeeded": "info", "cancelled": "warn"}.get(job.state, "error")
        self.events.add(level, f"job '{job.name}' {job.state}: {job.message}")

    def _owns_arm(self, ctx: JobContext) -> None:
        """Inside a job, under the lock: JobCancelled unless this job may still command the devices
        (it is current and not cancelled, or it is running its cleanup after a cancel), and never
        once the latch is set."""
        if self._job is not ctx.job or self._state not in JOB_STATES or self._halt.is_set():
            raise JobCancelled("job is no longer current")
        if not ctx.in_cleanup:
            ctx.check()

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
        """Inside a job: check the trajectory (check_motion), command it (only while this job owns the arm)
        and wait for it."""
        self.check_motion(trajectory)
        swept_box = self._swept_box(trajectory)
        with self._lock:
            self._owns_arm(ctx)
            self._command_arm(trajectory, swept_box)
        checked = ctx if not ctx.in_cleanup else None
        if not self._wait_until(lambda: not self.arm.is_moving(), trajectory.duration_s + 5.0, checked):
            self._halt_devices(gripper=False)
            if self._halt.is_set():
                raise JobCancelled("the station was e-stopped")
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
