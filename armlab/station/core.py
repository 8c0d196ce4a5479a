"""The Station, the gate: the state table, its lock and every state change; the only writer of arm commands.

Every command is checked against the transition table (states.py), the latch and the control lease under one lock,
and every state change goes through `_transition`, here. The lock guards state only: it is never held across I/O
(SQLite, IK, planning, scene changes). E-stop does not take it first: it sets the lock-free latch, cancels the job and
halts the arm and gripper, and only then records the state; every command path checks the latch under the lock before
it reaches a device, and every wait checks it, so after estop() returns no job or manual command can reach the arm
until reset(). A lost device (watch.py) latches the same way and puts the station in `fault`.
The parts the gate owns, each with its own state: latch (latch.py), lease (lease.py), gate (motion.py: every motion's
checks, send and waits), trust (calibration_trust.py), arm_calibration, teach (teach.py), perceiver (perceiving.py),
readings (status.py); and the command objects manual, cartesian, planned, job_commands. Skills, tasks and the server
call the Station's own methods; those a part answers are forwarded to it in one line (forwarding.py).
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from armlab.devices.arm import Arm
from armlab.devices.camera import Camera
from armlab.devices.clock import Clock, WallClock
from armlab.devices.gripper import Gripper
from armlab.errors import CommandRefused, DeviceLost, InvalidInput, NoArmError, ShuttingDown
from armlab.kinematics.calibrated_arm import CalibratedArm
from armlab.station.arm_calibration import ArmCalibrationKeeper
from armlab.station.arm_info import station_end_effector
from armlab.station.calibration_trust import SELF_RECALIBRATE_JOB, CalibrationTrust, self_recalibration_job
from armlab.station.cartesian_jog import CartesianJog
from armlab.station.checks import NotCalibrated
from armlab.station.colors import StationColors
from armlab.station.config import StationConfig
from armlab.station.event_history import EventHistory
from armlab.station.forwarding import forwarded
from armlab.station.held import HeldBlock
from armlab.station.intrinsics import CameraIntrinsics
from armlab.station.job_control import JobControls
from armlab.station.jobs import Job, JobCancelled, JobContext
from armlab.station.latch import Latch
from armlab.station.lease import ControlLease
from armlab.station.manual import ManualCommands
from armlab.station.memory import return_freed_memory
from armlab.station.motion import WAIT_CHUNK_S, MotionGate
from armlab.station.motion_record import MOTION_MEMORY
from armlab.station.perceiving import Perceiver
from armlab.station.perception import DEVICE_ERRORS
from armlab.station.planned_moves import PlannedMoves
from armlab.station.reach import ReachCache
from armlab.station.shutdown import stop_threads
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import ARM_COMMANDS, JOB_STATES, State, after_event, allowed_commands, next_state
from armlab.station.status import ArmReadings
from armlab.station.teach import Teach, TeachLinks
from armlab.station.telemetry import TelemetryPublisher
from armlab.station.watch import DeviceWatch, device_problems
from armlab.store import Owner, Store
from armlab.vision import detect_tags, load_perception_config
from armlab.workcell.loading import load_workcell_motion_config

log = logging.getLogger(__name__)

__all__ = ["DEVICE_ERRORS", "MOTION_MEMORY", "WAIT_CHUNK_S", "NotCalibrated", "Station"]


_UNLATCHED = ("estop",)  # the only command the latch and the lease never refuse


class Station:
    """The control station's gate: its state, the parts above, and the command objects it owns (station.manual,
    station.cartesian, station.planned, station.job_commands: manual.py, cartesian_jog.py, planned_moves.py,
    job_control.py), whose public methods it forwards. Backends are injected.

    model: the armlab.kinematics ArmModel (None: a station with no arm, perception only, every arm command refused
    with NoArmError); perception_config: armlab.vision's config; sim: the SimWorkcell when simulated (else None);
    synchronous: the sim runs in fast mode and nothing runs on threads (evaluations): frames are captured when asked
    and physics advances only while the gate waits. `source` (every command): the controller's name for the lease
    (None: an in-process caller, not leased).
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
        clock: Clock | None = None,
    ) -> None:
        if synchronous and (sim is None or sim.realtime):
            raise ValueError("synchronous mode needs a fast-mode simulation (SimWorkcell with realtime=False)")
        self.arm, self.gripper, self.camera = arm, gripper, camera
        # The one arm model every planner uses: the nominal one, corrected once the arm is calibrated
        # (set_arm_calibration swaps the calibration inside it; armlab.kinematics.calibrated_arm).
        self.model = CalibratedArm(model) if model is not None and hasattr(model, "ik_with_pitch") else model
        self.has_arm = model is not None
        self.config = config or StationConfig()
        self.store = store or Store(self.config.database_file())
        self.perception_config = perception_config
        self._motion_config = motion_config
        self.sim = sim
        # The motion clock: the simulation's own when simulated (its fast mode advances only while waited on), else
        # the wall clock; timeouts of motions, gripper settling and job waits are on it.
        self.clock: Clock = clock or (sim.clock if sim is not None else WallClock())
        self.backend = backend
        self.synchronous = synchronous
        self._lock = threading.RLock()
        # e-stop, device loss, a failed part (latch.py); a halt leaves no commanded motion to continue
        self.latch = Latch(arm, gripper, on_halt=lambda: self.gate.forget_commanded())
        self.gate = MotionGate(  # the one path of every motion: checks, start, send, waits, pacing, where it went (motion.py)
            arm, gripper, self.model, self.latch, self.clock, self._lock, motion_config=lambda: self.motion_config,
            end_effector=lambda: station_end_effector(self), held_block=lambda: self.held_block, state=self._effective_state,
            owns_arm=self._owns_arm, gripper_settle_timeout_s=self.config.gripper_settle_timeout_s,
            moving_speed_rad_s=self.config.moving_speed_rad_s)
        self._closing = threading.Event()
        self._state = State.IDLE
        self._detail = ""
        self._job: Job | None = None
        self._last_job: Job | None = None
        self._jog: dict | None = None  # the running jog: trajectory, start clock, velocity, controller
        self._held_block: HeldBlock | None = None  # what the last pick put in the gripper (held.py)
        self._torque_enabled = True  # connect() leaves the arm holding; set_torque() changes it
        self.events = EventLog()
        self.event_history = EventHistory(self.events, self.store)  # kept in the database (History panel)
        self.reach = ReachCache()  # where the gripper reaches on the board (the page's reach overlay)
        self.intrinsics = CameraIntrinsics(camera, self.store, self.events)  # in use: measured here, else the camera's own
        self.colors = StationColors(self.store, self.events, lambda: self.perception_config, lambda: self.calibration)  # defaults + samples
        self.perceiver = Perceiver(lambda: self.perception_config, self.model, lambda: self.trust.calibration, lambda: self.colors.model,
                                   lambda: self.latch.lost().get("camera"), self.config.camera_timeout_s,
                                   capture_now=sim.capture_next_frame if synchronous else None)  # frames on demand: no threads
        self.frames, self.perception = self.perceiver.frames, self.perceiver.results  # the newest frame and perception
        self.readings = ArmReadings(arm, gripper, self.model, self.config.moving_speed_rad_s)  # the status' device part
        self.telemetry: NewestSlot[dict] = NewestSlot()
        self.calibration_slot: NewestSlot[dict] = NewestSlot()
        self.lease = ControlLease(self.events, self._closing.is_set)  # who may command (lease.py)
        self.trust = CalibrationTrust(self.events, self.calibration_slot.publish, lambda: self.perception_config, self.config,
                                      self._why_not_self_recalibrate, self._start_self_recalibration, self.lease.check)  # in use, restored
        self.teach = Teach(self.store, self.events, lambda: self.program_owner, TeachLinks(  # late-bound: what the station does now
            self.allowed_or_raise, self._teach_transition, lambda: self.state is State.TEACH and not self.latch.is_set(),
            self._closing.is_set, lambda: self.joints_rad(), lambda: self.gripper.read_state().command,
            lambda q: self.check_pose(q), lambda poses: self.check_poses(poses), self.component_failed, threads=not synchronous))
        self.arm_calibration = ArmCalibrationKeeper(self.model, self.store, self.events, self.config.workcell)  # in use, saved
        # The command objects: each holds its own state and sends through the gate; their public methods are forwarded below.
        self.manual, self.cartesian = ManualCommands(self), CartesianJog(self)
        self.planned, self.job_commands = PlannedMoves(self), JobControls(self)
        self._workers: list = []
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
            self.perception_config = load_perception_config(workcell=self.config.workcell)  # the station's board and tags
        self.intrinsics.restore()
        self.colors.restore()
        interrupted = self.store.mark_interrupted_jobs()
        if interrupted:
            self.events.add("warn", f"{interrupted} job(s) were cut off when the station last stopped: marked interrupted")
        if self.config.restore_calibration:
            one_look = (lambda: detect_tags(self.fresh_frame().color_bgr, self.perception_config)) if self.perceiver.on_demand else None
            self.trust.restore(self.store.latest_calibration(), one_look)
            self.arm_calibration.restore()
        self._closing.clear()
        if not self.synchronous:
            self._workers = [
                *self.perceiver.threads(self.camera, self.arm, self.gripper, self.config.perception_rate_hz, self.trust.to_check,
                                        self.trust.on_check),
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
        self._latch_and_halt()

    def close(self) -> dict:
        """Stop the job and the threads (each join bounded by close_timeout_s), halt the arm.

        Returns {"joined": [thread names], "alive": [names still running]} and logs it; the devices (or
        the sim) are closed by their owner."""
        self.begin_shutdown()
        job = self._job or self._last_job  # a job cancelled by begin_shutdown may have just ended
        report = stop_threads(None if job is None else job.thread, self._workers, self.event_history.close,
                              self.config.close_timeout_s)
        self._workers, self._started = [], False
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
            return allowed_commands(self._effective_state(), self.has_arm)

    def allowed_or_raise(self, command: str, source: str | None = None) -> None:
        """CommandRefused (naming the allowed commands) unless `command` is allowed right now;
        NotController if `source` may not command (the lease is not taken by this check)."""
        with self._lock:
            self._check(command, source)

    def _effective_state(self) -> State:
        """The state, or estop while the latch is set ahead of the transition (caller holds the lock)."""
        if self.latch.is_set() and self._state not in (State.ESTOP, State.FAULT):
            return State.ESTOP
        return self._state

    def _check(self, command: str, source: str | None) -> State:
        """Refusals of an operator command, in order: shutting down, the latch/state table, the lease.
        Returns the state it would lead to. Caller holds the lock."""
        if self._closing.is_set() and command not in _UNLATCHED:
            raise ShuttingDown(f"command '{command}' refused: the station is shutting down")
        if not self.has_arm and command in ARM_COMMANDS:
            raise NoArmError(command, self._effective_state().value, allowed_commands(self._effective_state(), False))
        new_state = next_state(self._effective_state(), command)
        if command not in _UNLATCHED:
            self.lease.check(source, command)  # NotController naming the holder
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
            if trigger not in _UNLATCHED:
                self.lease.require(source, trigger)  # a free lease goes to `source` (announced)
        if new_state is not self._state or detail is not None:
            self._detail = detail if detail is not None else ("" if new_state is State.IDLE else self._detail)
        self._state = new_state
        return new_state

    # The latch: e-stop, device loss, reset ----------------------------------------------------------

    def _latch_and_halt(self) -> list[str]:
        """Set the latch first, cancel the job, halt the arm and gripper (before any lock): what fails to stop."""
        self.latch.set()
        job = self._job
        if job is not None:
            job.cancel(halted=True)
        return self.latch.halt_devices()

    def estop(self, source: str | None = None) -> None:
        """Halt now and latch, from any state and from anyone (no lease needed): latch first, cancel the
        job, stop arm and gripper, then record the state; a command that was being sent when the latch
        went up is stopped by a second halt once the lock shows it has finished."""
        failures = self._latch_and_halt()
        with self._lock:
            self._jog = None
            by = f" by '{source}'" if source else ""
            self._transition("estop", source=source, detail=f"e-stop pressed{by}: reset to continue")
        failures += self.latch.halt_devices()
        self.events.add("error", "E-stop: motion halted" + (f" ({'; '.join(sorted(set(failures)))})" if failures else ""))

    def device_problems(self) -> dict[str, str]:
        """{device: reason} for each device not answering now (watch.py); empty when all answer."""
        return device_problems(self.arm, self.gripper, lambda: self.perceiver.camera_problem() if self._started else None)

    def _on_device_problems(self, problems: dict[str, str]) -> None:
        """The device watch's report: fault on a new loss, log a recovery (the station stays in fault)."""
        new, back = self.latch.note_problems(problems)
        for name in back:
            self.events.add("info", f"{name} answers again: reset to continue")
        if new:
            self.device_failed(", ".join(new), "; ".join(new.values()))

    def _fault(self, detail: str) -> None:
        """Latch, cancel the job, hold the arm still, enter fault with `detail`."""
        self._latch_and_halt()
        with self._lock:
            self._jog = None
            if self._transition("device_failed", event=True) is State.FAULT:
                self._detail = detail

    def device_failed(self, device: str, reason: str) -> None:
        """A device is lost: latch, cancel the job, hold the arm still, enter fault with the reason."""
        self._fault(f"{device} lost: {reason}; reset once it is back")
        self.events.add("error", f"{device} lost: {reason}: motion halted")

    def component_failed(self, what: str, reason: str) -> None:
        """A part of the station died (e.g. the teach recorder's thread): latch, cancel the job, hold the arm
        still, enter fault with the reason, log it. Reset clears it (no device to wait for)."""
        self._fault(f"{what} failed: {reason}; reset to continue")
        log.error("%s failed: %s: motion halted, station in fault", what, reason)
        self.events.add("error", f"{what} failed: {reason}: motion halted")

    def reset(self, source: str | None = None) -> None:
        """Leave estop/fault for idle without moving the arm; DeviceLost while a device is still gone."""
        with self._lock:
            if self._state not in (State.ESTOP, State.FAULT):  # not while an e-stop is still being recorded
                raise CommandRefused("reset", self._effective_state().value, allowed_commands(self._effective_state()))
            self._check("reset", source)
        problems = self.device_problems()  # device reads: outside the lock
        if problems:
            self.latch.add_lost(problems)
            raise DeviceLost("reset refused: " + "; ".join(f"the {name} is still lost ({reason})" for name, reason in problems.items()))
        with self._lock:
            self._transition("reset", source=source, detail="")
            back = self.latch.forget_lost()
            self.latch.clear()
        for name in back:
            self.events.add("info", f"{name} answers again")
        self.events.add("info", "reset: station idle")

    # Control lease (the part: station.lease, lease.py) ----------------------------------------------

    controller = forwarded("lease", "holder")  # who holds the control lease (None: free)

    def require_control(self, command: str, source: str | None) -> None:
        """The lease check of a command outside the state table (program edits): NotController naming the
        holder, ShuttingDown while closing; a free lease goes to `source`, as a motion command takes it."""
        with self._lock:
            if self._closing.is_set():
                raise ShuttingDown(f"command '{command}' refused: the station is shutting down")
            self.lease.require(source, command)

    def take_control(self, source: str) -> str | None:
        """Take the control lease over (explicitly; announced to everyone, the previous holder too). Returns the previous holder."""
        with self._lock:
            return self.lease.take(source)

    def release_control(self, source: str, reason: str = "released") -> bool:
        """Give the lease up if `source` holds it (reason: e.g. 'disconnected'), ending its jog; True if it did."""
        with self._lock:
            released = self.lease.release(source, reason)
            if released and self._jog is not None and self._jog["source"] == source:
                self._jog = None
        return released

    # Teach (the part: teach.py) -------------------------------------------------------------------

    @property
    def program_owner(self) -> Owner | None:
        """Whose programs and draft this station reads and writes: its arm and workcell (None: no arm, all rows)."""
        return None if self.model is None else Owner(str(self.model.name), getattr(self.config, "workcell", None), int(self.model.dof))

    def _teach_transition(self, command: str, source: str | None, detail: str, only_in_teach: bool = False) -> None:
        with self._lock:
            if not only_in_teach or self._effective_state() is State.TEACH:
                self._transition(command, source=source, detail=detail)

    # Calibration (the part: calibration_trust.py) ---------------------------------------------------

    calibration, calibration_info = forwarded("trust", "calibration"), forwarded("trust", "info")
    set_calibration, require_trusted_calibration = forwarded("trust", "install"), forwarded("trust", "require_trusted")

    def _why_not_self_recalibrate(self) -> str | None:
        """None when the station may recalibrate itself now (idle, nothing running, the arm still), else why not."""
        recording = self.teach.has_recorder  # teach's lock is never taken under the gate's
        with self._lock:
            if self.latch.is_set() or self._closing.is_set() or self._state is not State.IDLE:
                return f"the station is {self._effective_state().value}"
            if self._job is not None or self._jog is not None or recording:
                return "a job or a jog is running"
        return self.gate.arm_moving()

    def _start_self_recalibration(self) -> None:
        self.start_job("calibrate", SELF_RECALIBRATE_JOB, lambda ctx: self_recalibration_job(self, ctx),
                       detail="camera moved: recalibrating from the board tags")

    @property
    def motion_config(self) -> Any:
        """armlab.motion's MotionConfig (config/motion.yaml with the workcell's `motion:` overrides, unless one
        was injected)."""
        if self._motion_config is None:
            self._motion_config = load_workcell_motion_config(self.config.workcell)
        return self._motion_config

    @property
    def held_block(self) -> HeldBlock | None:
        """What the last pick put in the gripper (held.HeldBlock: its edge, colour, size, yaw), or None."""
        with self._lock:
            return self._held_block

    def set_held_block(self, block: HeldBlock | None) -> None:
        """A pick put `block` in the gripper (None: it is empty); TypeError for anything but a HeldBlock."""
        if block is not None and not isinstance(block, HeldBlock):
            raise TypeError(f"set_held_block takes a HeldBlock or None, not {type(block).__name__}")
        with self._lock:
            self._held_block = block

    def _owns_arm(self, ctx: JobContext) -> None:
        """Inside a job, under the lock: JobCancelled unless this job may still command the devices
        (it is current and not cancelled, or it is running its cleanup after a cancel), and never
        once the latch is set."""
        if self._job is not ctx.job or self._state not in JOB_STATES or self.latch.is_set():
            raise JobCancelled("job is no longer current")
        if not ctx.in_cleanup:
            ctx.check()

    def set_scene(self, scene: Any, source: str | None = None) -> None:
        """Simulation: replace the objects (armlab.scene Scene). Checked (state, lease) under the lock; the
        scene change itself runs outside it, so an e-stop never waits for it."""
        if self.sim is None:
            raise InvalidInput("set_scene needs the simulation backend")
        with self._lock:
            self._transition("set_scene", source=source)
        _, version = self.frames.get()
        self.sim.set_scene(scene)
        self.gate.record.note_change_everywhere()  # what the arm hides now was seen in the old scene
        self.set_held_block(None)
        self.perceiver.wait_for_new_frame(version, timeout_s=1.0)  # once one of the new scene is drawn, the old model's memory is free
        return_freed_memory()

    # Status and what the gate sees (perceiving.py, status.py) ---------------------------------------

    def status(self) -> dict:
        """GET /api/status: the wire dict (SI units). Works with a device lost (its last reading is shown)."""
        readings = self.readings.read()
        with self._lock:
            job = self._job or self._last_job
            state, detail, lease = self._effective_state(), self._detail, self.lease.to_dict()
        perception, _ = self.perception.get()
        commanded = self.gate.commanded_joints_rad() if self.has_arm else None
        return {
            "state": state.value, "detail": detail, **readings,
            "commanded_joints_rad": None if commanded is None else [float(v) for v in commanded],
            "torque_enabled": self._torque_enabled, "calibrated": self.trust.calibration is not None,
            "camera_warning": perception.camera_warning if self.trust.checked and perception is not None else None,
            "calibration_state": self.trust.state, "self_recalibrate": self.trust.self_recalibrate,
            "arm_calibration": self.arm_calibration.status if self.has_arm else None,
            "backend": self.backend, "controller": lease["controller"], "controller_since_s": lease["since_s"],
            "devices_lost": self.latch.lost(), "speed_percent": self.gate.speed_percent,
            "job": job.to_dict() if job is not None else None, "allowed_commands": allowed_commands(state, self.has_arm),
            "time_s": time.time(),
        }

    def telemetry_snapshot(self) -> dict:
        """Status + detections: one telemetry message (the TelemetryPublisher calls this)."""
        snapshot, detections = self.status(), self.detections()
        snapshot["detections"], snapshot["detections_stale"] = detections.to_dict()["data"], detections.stale
        return snapshot

    # What the parts answer (the part's method is the one place each is written) ------------------------------------

    detections, fresh_frame, frame_after, fresh_perception = (forwarded("perceiver") for _ in range(4))
    clock_s, joints_rad = forwarded("gate"), forwarded("gate")
    # the motion gate's commands inside a job (skills, tasks) and its waits
    run_trajectory, start_trajectory, replace_trajectory, wait_in_job = (forwarded("gate") for _ in range(4))
    run_gripper, brake_to_rest, wait_motion, wait_gripper, settle_arm = (forwarded("gate") for _ in range(5))
    fingers_still_check, note_gripper_change = forwarded("gate"), forwarded("gate")
    # the commanded motion, and the speed override it is paced at
    start_position, motion_handover, commanded_joints_rad = (forwarded("gate") for _ in range(3))
    commanded_motion_running, arm_moving, speed_percent = (forwarded("gate") for _ in range(3))
    # the trajectory check (motion_check.py) and where the gripper went (motion_record.py)
    check_motion, check_pose, check_poses, check_body = (forwarded("gate.check") for _ in range(4))
    checked_joints, palm_corners_m, finger_box = (forwarded("gate.check") for _ in range(3))
    moved_over_since, changed_at_since, note_change_everywhere = (forwarded("gate.record") for _ in range(3))
    # the operator's commands (manual.py, cartesian_jog.py, planned_moves.py, job_control.py)
    move_joints, home, sleep, move_to, move_in_job = (forwarded("manual") for _ in range(5))
    plan_move, plan_move_from, solve_pose, check_move = (forwarded("manual") for _ in range(4))
    jog, step_gripper, heartbeat, set_torque, gripper_command = (forwarded("manual") for _ in range(5))
    jog_cartesian, stop_jog = forwarded("cartesian"), forwarded("cartesian")
    plan_only, plan_motion, plan_steps, plan_job = (forwarded("planned") for _ in range(4))
    execute_plan, discard_plan, plan_wire = (forwarded("planned") for _ in range(3))
    start_job, cancel_job, current_job, set_speed = (forwarded("job_commands") for _ in range(4))
    pause_job, resume_job, step_job, plan_job_step, set_job_speed = (forwarded("job_commands") for _ in range(5))
    set_arm_calibration, arm_rig_key = forwarded("arm_calibration", "install"), forwarded("arm_calibration", "rig_key")

    def require_arm(self, what: str) -> None:
        """NoArmError naming `what` on a station without an arm (for work that needs the arm's model, e.g. programs)."""
        if not self.has_arm:
            with self._lock:
                raise NoArmError(what, self._effective_state().value, allowed_commands(self._effective_state(), False))
