"""The motion gate: the one path every motion takes to the arm, owned by core.Station (station.gate).

Every trajectory from any source (manual, jog, jobs) passes `check_motion` (motion_check.py: limits, velocity and
acceleration, the table, the workspace box, the per-step jump, the body) outside the lock and `command_arm` (latch,
start at the measured joints, continuity with the motion it replaces) under it, inside `sending()`, which sends to the
device once the lock is released (on the real arm a ROS service call: status and telemetry never wait for it) and
halts again if the latch went up meanwhile. Waits are on the injected Clock, return at once when the latch is set and,
in fast mode, never let the physics run more than one control period past it. It paces what it sends at the speed
override (armlab.motion.time_warp, within planning_limits) and records where the gripper went (motion_record.py).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.devices.clock import Clock
from armlab.errors import PLAN_REFUSALS, ArmMoving, CommandRefused, InvalidInput
from armlab.motion.blend import arm_limits, plan_stop
from armlab.motion.end_effector import EndEffector
from armlab.motion.handover import Handover, continuity_problem, reference_velocity, splice, take_over, trimmed
from armlab.motion.planning_limits import planning_accel_rad_s2
from armlab.motion.safety import UnsafeTrajectory, check_start
from armlab.motion.time_warp import paced
from armlab.station.held import HeldBlock
from armlab.station.job_control import SPEED_WAIT_FACTOR
from armlab.station.jobs import JobCancelled, JobContext
from armlab.station.latch import Latch
from armlab.station.motion_check import MotionCheck
from armlab.station.motion_record import MotionRecord
from armlab.station.settle import ARRIVE_TIMEOUT_S, arrived, settle_at_rest
from armlab.station.states import State, allowed_commands
from armlab.station.status import arm_turning

WAIT_CHUNK_S = 0.05  # waits on the devices check cancel/e-stop this often (simulated time in fast mode)


class HandoverLate(RuntimeError):
    """A planned handover can no longer be used (its moment passed, or another motion was commanded): plan again."""


class MotionGate:
    """Waiting on the devices and sending motion: the commanded motion, the send queue, the speed override.

    lock: the station's lock (core.py), so a command's state transition and its send are checked as one step;
    state(): the station's state as commands see it (the caller holds the lock); owns_arm(ctx): JobCancelled unless
    that job may still command the arm (core.py, under the lock); motion_config(): the MotionConfig (read late);
    end_effector(), held_block(): for the body check (motion_check.py)."""

    def __init__(self, arm: Any, gripper: Any, model: Any, latch: Latch, clock: Clock, lock: threading.RLock, *,
                 motion_config: Callable[[], Any], end_effector: Callable[[], EndEffector],
                 held_block: Callable[[], HeldBlock | None], state: Callable[[], State], owns_arm: Callable[[JobContext], None],
                 gripper_settle_timeout_s: float, moving_speed_rad_s: float) -> None:
        self.arm, self.gripper, self.model, self.latch, self.clock = arm, gripper, model, latch, clock
        self._lock, self.motion_config, self._state_now, self._owns_arm = lock, motion_config, state, owns_arm
        self._settle_timeout_s, self._moving_speed_rad_s = gripper_settle_timeout_s, moving_speed_rad_s
        self.check = MotionCheck(model, motion_config, end_effector, held_block)  # check_motion, check_pose, ...
        self.record = MotionRecord(model)  # where the gripper went and when (stale perception)
        self._plan_lock = threading.RLock()  # one replacing motion planned at a time (send_replacing)
        self._newest_move = 0  # the ticket of the newest manual move waiting to be planned (send_replacing)
        self._send_lock = threading.Lock()  # one sender of device commands at a time, taken before the lock (sending)
        self._outbox: list | None = None  # device commands queued under the lock, sent after it (sending)
        self._commanded: tuple | None = None  # the last trajectory sent: (trajectory, clock_s at its t = 0, count)
        self.settled_toward: tuple | None = None  # settle.settle_at_rest's last: (command count, the step's end it corrected to)
        self._command_count = 0
        self._speed_lock = threading.Lock()  # one override change (or paced send) at a time
        self._speed_percent = 100.0  # the speed override every motion is paced at (set by job_control.py set_speed)
        self._paced_motion: tuple | None = None  # (the trajectory object last sent, the override it was paced at)
        self._pace_next: float | None = None  # the override of the motion being sent (set under the lock just before it)

    def clock_s(self) -> float:
        """The motion clock's time (simulated time on the simulation, else monotonic wall time)."""
        return self.clock.now_s()

    def joints_rad(self) -> np.ndarray:
        """The measured joint positions (rad)."""
        return np.asarray(self.arm.read_joint_state().position_rad, dtype=float)

    @property
    def commanded(self) -> tuple | None:
        """The last trajectory sent: (trajectory, clock_s at its t = 0, its count), or None (nothing sent, or halted)."""
        return self._commanded  # one attribute read: atomic; the tuple is never changed in place

    @property
    def command_count(self) -> int:
        """How many motions were commanded (a new revision of a motion's start counts too)."""
        with self._lock:
            return self._command_count

    def forget_commanded(self) -> None:
        """A halt or the torque switched: the arm holds where it is, so there is no commanded motion to continue."""
        self._commanded = None

    # The speed override (the command: job_control.py) ---------------------------------------------------------------

    @property
    def speed_percent(self) -> float:
        return self._speed_percent

    def paced(self, trajectory: JointTrajectory, percent: float, from_rest: bool | None = None) -> JointTrajectory:
        """A newly planned motion at `percent` (armlab.motion.time_warp.paced); from_rest None: it starts from rest
        unless a commanded motion is still running."""
        if from_rest is None:
            from_rest = not self.commanded_motion_running()
        return paced(trajectory, percent / 100.0, planning_accel_rad_s2(self.model), from_rest, self.motion_config().sample_rate_hz)

    def pace_next_send(self, percent: float) -> None:
        """Under the lock, just before command_arm: the motion about to be sent was paced at `percent` (a later
        change re-times it); HandoverLate (plan again) when the override has changed since it was planned."""
        if percent != self._speed_percent:
            raise HandoverLate(f"the speed override changed to {self._speed_percent:g} % while this motion was planned")
        self._pace_next = percent

    @contextmanager
    def speed_change(self) -> Iterator[None]:
        """`with gate.speed_change():` one override change at a time; paced sends wait for it."""
        with self._speed_lock:
            yield

    def set_speed_percent(self, speed: float) -> float:
        """The new override (caller is inside speed_change()); returns the old one."""
        with self._lock:
            old, self._speed_percent = self._speed_percent, speed
        return old

    @property
    def paced_motion(self) -> tuple | None:
        """(the trajectory object last sent, the override it was paced at), None before any: what a change re-times."""
        return self._paced_motion

    # Waiting and sending -------------------------------------------------------------------------------------------

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float, ctx: JobContext | None = None) -> bool:
        """Block until predicate() holds (False after timeout_s of motion-clock time, or at once when the
        latch is set). On the simulation this lets fast mode advance the physics, never beyond one
        control period after the latch; a job's cancel is checked every WAIT_CHUNK_S."""
        deadline = self.clock_s() + timeout_s
        latched = self.latch.is_set
        while True:
            if ctx is not None:
                ctx.check()
            if latched():
                if ctx is not None and not ctx.in_cleanup:
                    raise JobCancelled("the station was e-stopped")
                return predicate()
            if self.clock.wait_for(lambda: predicate() or latched(), WAIT_CHUNK_S) and not latched():
                return True
            if self.clock_s() > deadline:
                return predicate()

    def wait_motion(self, timeout_s: float) -> bool:
        """Block until the arm stops; False on timeout."""
        return self.wait_until(lambda: not self.arm.is_moving(), timeout_s)

    def wait_gripper(self, ctx: JobContext | None = None) -> None:
        """Wait until the fingers stop moving (≤ gripper_settle_timeout_s of motion-clock time)."""
        self.wait_until(self.fingers_still_check(), self._settle_timeout_s, ctx)

    def fingers_still_check(self) -> Callable[[], bool]:
        """A fresh predicate, true once the fingers' width stayed within 0.2 mm for 0.15 s (motion clock)
        since it was first called: what a gripper wait waits for (also the server's ?wait=true)."""
        still = {"width": None, "since": self.clock_s()}

        def fingers_still() -> bool:
            width, now = self.gripper.read_state().width_m, self.clock_s()
            if still["width"] is None or abs(width - still["width"]) > 2e-4:
                still["width"], still["since"] = width, now
                return False
            return now - still["since"] > 0.15

        return fingers_still

    @contextmanager
    def sending(self) -> Iterator[None]:
        """`with self.sending():` instead of `with self._lock:` around checks that end in device commands: the
        body runs under the lock and queues its commands (send_later), which are sent after the lock is
        released, in order, one sender at a time (so the device sees commands in the order they were checked).
        The latch and a cancel still win: a command checked before a halt (e-stop, fault, cancel) and sent after
        it is halted again here (e-stop sets the latch before it halts, so either its halt comes after this send
        or this check sees it). Never enter it holding the lock. A body that raises sends nothing."""
        with self._send_lock:
            outbox: list[Callable[[], object]] = []
            with self._lock:
                halts = self.latch.halts
                self._outbox = outbox
                try:
                    yield
                finally:
                    self._outbox = None
            for send in outbox:
                send()
            if outbox and (self.latch.is_set() or self.latch.halts != halts):
                self.latch.halt_devices(gripper=self.latch.is_set())

    def send_later(self, send: Callable[[], object]) -> None:
        """Queue a device command for when the lock is released (caller is inside `sending()`)."""
        if self._outbox is None:
            raise RuntimeError("device commands are sent from inside MotionGate.sending(), never under the bare lock")
        self._outbox.append(send)

    def command_arm(self, trajectory: JointTrajectory, swept_box: np.ndarray, handover: Handover | None = None,
                     planned_after: int | None = None) -> JointTrajectory:
        """Send a checked trajectory and remember it and where the gripper sweeps; returns what was sent.
        Caller is inside `sending()` (holds the lock; the trajectory reaches the arm once the lock is released)
        and has checked the state; checked here: the latch, the start (no jump from the
        measured joints) and, while a commanded motion runs, that this one continues it: a splice from
        `handover` (taken from that very motion; trimmed to now: HandoverLate when now is past the handover)
        or a trajectory starting at the running reference and its velocity (ArmMoving otherwise). Either is sent
        with its start on the arm's clock (Arm.command_trajectory's start_time_s: the station's clock is the arm's),
        so a send held up after the check still continues the running curve; a motion from rest starts when the
        arm takes it, and the record follows (_started_at)."""
        state = self._state_now()
        if self.latch.is_set():
            raise CommandRefused("move", state.value, allowed_commands(state))
        now = self.clock_s()
        running = self._commanded
        planned, planned_t0 = trajectory, now  # remembered untrimmed: a later handover keeps its sample grid
        continues = False  # sent while a commanded motion runs at speed (then on the station's clock)
        if handover is None and planned_after is not None and planned_after != self._command_count:
            raise HandoverLate("another motion was commanded while this one was planned from rest")
        if handover is not None:
            if running is None or running[2] != handover.source_id:
                raise HandoverLate("another motion was commanded since the handover was planned")
            elapsed = now - handover.planned_at_s
            if elapsed > handover.lead_s - 1e-9:
                raise HandoverLate(f"the handover {handover.lead_s - elapsed:.3f} s ago has passed (planning was slower than the lead)")
            trajectory = trimmed(trajectory, elapsed)
            planned_t0 = handover.planned_at_s
        elif running is not None and now - running[1] < running[0].duration_s:
            velocity = reference_velocity(running[0], now - running[1])
            # Slower than one sample's worth of acceleration from rest, a plan from rest continues it as well.
            slow_rad_s = np.asarray(self.model.accel_limit_rad_s2, float) / self.motion_config().sample_rate_hz
            if np.any(np.abs(velocity) > slow_rad_s):
                continues = True
                position = running[0].sample(now - running[1])
                problem = continuity_problem(trajectory, position, velocity, self.model.accel_limit_rad_s2, self.model.joint_names)
                if problem is not None:
                    raise ArmMoving("move", state.value, allowed_commands(state), f"the new motion does not continue it: {problem}")
        measured, read_s = self.joints_rad(), self.clock_s()
        try:
            self._check_start(trajectory, measured)
        except UnsafeTrajectory:
            if read_s <= now:
                raise
            # The physics ran on between the check's clock and the reading (a CPU-starved batch): the arm is that much
            # further along the commanded curve, where the trajectory is at the reading's time.
            self._check_start(trimmed(trajectory, read_s - now), measured)
        self._command_count += 1
        record = self._commanded = (planned, planned_t0, self._command_count)
        self._paced_motion, self._pace_next = (planned, self._pace_next), None  # what a change of the override re-times
        if handover is not None:  # the arm samples the splice at its own clock minus this: a late send continues it
            start_s = handover.planned_at_s + max(elapsed, 0.0)  # (before 0: a motion from rest not begun yet, as it will)
            self.send_later(lambda: self.arm.command_trajectory(trajectory, start_time_s=start_s))
        elif continues:  # it starts at the running reference now: the same, from now
            self.send_later(lambda: self.arm.command_trajectory(trajectory, start_time_s=now))
        else:  # from rest: a late send starts late without a jump, and the record follows the arm's start
            self.send_later(lambda: self._started_at(record, self.arm.command_trajectory(trajectory)))
        self.record.add(trajectory.duration_s, swept_box)
        return trajectory

    def _check_start(self, trajectory: JointTrajectory, measured: np.ndarray) -> None:
        """UnsafeTrajectory unless the trajectory starts within start_tolerance_rad of the readings or of the command
        holding the arm there (model.command_holding): a step chained from the last one's commanded end starts at the
        latter, the real RX200's readings 0.04-0.05 rad below it at far reach (its servos' steady error)."""
        tolerance, names = self.motion_config().start_tolerance_rad, self.model.joint_names
        try:
            check_start(trajectory, measured, tolerance, names)
        except UnsafeTrajectory:
            command = self.holding_command(measured)
            if np.abs(command - measured).max() < 1e-9:
                raise
            check_start(trajectory, command, tolerance, names)

    def holding_command(self, q_read) -> np.ndarray:
        """The command holding the arm where it reads q_read (model.command_holding: the readings less the servos'
        steady error under its weight); the readings themselves where the model knows no such error."""
        holding = getattr(self.model, "command_holding", None)
        return np.asarray(q_read, float) if holding is None else holding(q_read)

    def _started_at(self, record: tuple, started_s) -> None:
        """After a motion from rest was sent: remember the arm's own start time of it (a send held up starts
        later than the station's check), so a takeover planned from it continues what the arm really runs. A
        new revision: a handover already planned from the old start is late (HandoverLate: planned again)."""
        if not isinstance(started_s, (int, float)) or not np.isfinite(started_s):
            return  # an arm that does not say when it started
        with self._lock:
            if self._commanded is record and started_s != record[1]:
                self._command_count += 1
                self._commanded = (record[0], float(started_s), self._command_count)

    def arm_moving(self) -> str | None:
        """'the arm is moving' (a commanded motion not yet over, or joints turning), a read failure, else None."""
        if self.record.last_end_s() > self.record.now_s():
            return "the arm is moving"
        try:
            if arm_turning(self.arm, self.arm.read_joint_state(), self._moving_speed_rad_s):
                return "the arm is moving"
        except (ConnectionError, TimeoutError, OSError) as error:
            return f"the arm cannot be read ({error})"
        return None

    def commanded_joints_rad(self) -> np.ndarray | None:
        """The commanded reference now (rad): the last trajectory sent, sampled at the station's clock (its end once
        it has run out); None before any motion was sent or after a halt. Reads one attribute, takes no lock: a
        recorder samples it at 100 Hz."""
        running = self._commanded  # one attribute read: atomic; the tuple is never changed in place
        if running is None:
            return None
        trajectory, t0_s = running[0], running[1]
        return np.asarray(trajectory.sample(min(max(0.0, self.clock_s() - t0_s), trajectory.duration_s)), dtype=float)

    def start_position(self) -> np.ndarray:
        """Where a motion from rest starts: the position the servos were last commanded to hold (the end of the
        last trajectory sent, also in its last two samples) while the command holding the arm where it is measured
        (model.command_holding: the readings less the servos' steady error under its weight) is within half the start
        tolerance of it, so the command does not step by the servos' error; else (moving, halted, limp, pushed away)
        the measured joints."""
        measured = self.joints_rad()
        with self._lock:
            running = self._commanded
        if running is None:
            return measured
        # A motion in its last two samples is as good as at rest there: the measured joints trail the command by the
        # servos' lag, and a run planned from them stepped the command by that lag (1.9 mrad in one 4 ms tick).
        if running[0].duration_s - (self.clock_s() - running[1]) > 2.0 / self.motion_config().sample_rate_hz:
            return measured
        held = running[0].positions_rad[-1]
        command = self.holding_command(measured)  # the servos' steady error taken off
        if float(np.max(np.abs(held - command))) > 0.5 * self.motion_config().start_tolerance_rad:
            return measured
        return held.copy()

    def commanded_motion_running(self) -> bool:
        """Whether the last trajectory sent has yet to reach its end on the station's clock (a motion sent but not yet
        taken by the arm counts; one that ended counts no more, though a handover still holds its last sample period)."""
        running = self._commanded  # one attribute read: atomic
        return running is not None and self.clock_s() - running[1] < running[0].duration_s

    def motion_handover(self, lead_s: float | None = None) -> Handover | None:
        """Where a motion replacing the commanded one takes over (lead_s, default handover_lead_s, from now),
        or None when no commanded motion is running (plan from the measured joints, at rest)."""
        with self._lock:
            running = self._commanded
        if running is None:
            return None
        config = self.motion_config()
        lead = config.handover_lead_s if lead_s is None else lead_s
        return take_over(running[0], running[1], self.clock_s(), lead, config.sample_rate_hz, running[2])

    def send_replacing(self, plan: Callable, under_lock: Callable[[], None] | None = None, command: str = "move",
                        replaceable: bool = False) -> tuple[JointTrajectory, Handover | None]:
        """Plan (plan(handover) -> the new trajectory, from the handover's state, or from the measured joints
        when it is None), check and send a motion that replaces whatever runs, continuously. under_lock() runs
        with the lock held just before sending (state transitions, the job's ownership). A handover missed
        because planning was slow is retried with a longer lead (twice), then ArmMoving. Returns (the
        trajectory as planned, spliced; the handover or None).

        One motion is planned at a time: commands sent together (a script's burst, 42 clients) otherwise plan side
        by side, each from a handover the next one makes late, and the CPU-bound planners starve status, the waits
        and the physics. A replaceable one (a manual move) that a newer manual move overtook while it waited its
        turn is refused unplanned (ArmMoving): it would be replaced as soon as it started."""
        lead = self.motion_config().handover_lead_s
        if replaceable:
            with self._lock:
                self._newest_move += 1
                ticket = self._newest_move
        with self._plan_lock:
            with self._lock:
                state = self._state_now()
                overtaken = replaceable and ticket != self._newest_move
            if self.latch.is_set():  # e-stopped while this waited its turn: refused at once, as it would be after planning
                raise CommandRefused(command, state.value, allowed_commands(state))
            if overtaken:
                raise ArmMoving(command, state.value, allowed_commands(state),
                                "a newer move came in while this one waited to be planned: the newer one replaces it")
            for _ in range(3):
                with self._lock:
                    seen = self._command_count
                handover = self.motion_handover(lead)
                new = plan(handover)
                trajectory = splice(handover, new) if handover is not None else new
                self.check.check_motion(trajectory)
                swept_box = self.record.swept_box(trajectory)
                try:
                    with self.sending():
                        if under_lock is not None:
                            under_lock()
                        self.command_arm(trajectory, swept_box, handover, planned_after=seen)
                    return trajectory, handover
                except HandoverLate:
                    lead *= 2.0
        with self._lock:
            state = self._state_now()
        raise ArmMoving(command, state.value, allowed_commands(state), "planning could not keep up with the motion in progress")

    def brake_to_rest(self, ctx: JobContext | None = None) -> None:
        """Bring a motion in progress to rest on a jerk-limited stop at the arm's limits (no-op at rest), and
        wait until the arm stands still. Inside a job only while the job owns the arm."""
        handover = self.motion_handover()
        if handover is None and not self.arm.is_moving():
            return
        if handover is not None and not handover.at_rest:
            limits = arm_limits(self.model)
            rate = self.motion_config().sample_rate_hz

            def stop(handover: Handover | None) -> JointTrajectory:
                if handover is None:
                    raise HandoverLate("the motion ended meanwhile")
                return plan_stop(handover.position_rad, handover.velocity_rad_s, handover.accel_rad_s2, limits, rate)

            owns = (lambda: self._owns_arm(ctx)) if ctx is not None else None
            try:
                self.send_replacing(stop, owns, "stop")
            except (HandoverLate, *PLAN_REFUSALS):  # the motion ended meanwhile, or the stop fails its check: it runs out
                pass
        self.wait_until(lambda: not self.arm.is_moving(), 30.0, ctx)

    def note_gripper_change(self) -> None:
        """A grasp or release where the gripper is: a change there for changed_at_since (no motion of the arm)."""
        if self.model is None:
            return
        try:
            point = np.asarray(self.model.fk(self.joints_rad()), float)[:3, 3]
        except (ConnectionError, TimeoutError, OSError):  # the arm not answering: its own fault path reports that
            return
        self.record.note_gripper_change_at(point)

    def start_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> JointTrajectory:
        """Inside a job: check the trajectory (check_motion) and command it (only while this job owns the
        arm), without waiting; while a motion runs it must continue it (replace_trajectory plans one that does).
        Paced at the speed override unless the job paces itself (a repeat's RunControl). Returns
        what was sent."""
        paces = getattr(ctx.job, "control", None) is None
        with self._speed_lock:  # a change of the override waits for this send, then re-times it
            speed = self._speed_percent
            if paces:
                trajectory = self.paced(trajectory, speed)
            self.check.check_motion(trajectory)
            swept_box = self.record.swept_box(trajectory)
            with self.sending():
                self._owns_arm(ctx)
                if paces:
                    self.pace_next_send(speed)
                self.command_arm(trajectory, swept_box)
        return trajectory

    def replace_trajectory(self, ctx: JobContext, plan: Callable) -> tuple[JointTrajectory, float, float]:
        """Inside a job: replace the motion in progress by plan(handover) (see send_replacing), continuously.
        Returns (the command as spliced, the clock time of its t = 0, the clock time the new plan starts).
        ValueError / UnsafeTrajectory when the plan cannot be made or fails the check: nothing changes, the
        motion in progress goes on."""
        trajectory, handover = self.send_replacing(plan, lambda: self._owns_arm(ctx))
        if handover is None:
            start = self._commanded[1]
            return trajectory, start, start
        return trajectory, handover.planned_at_s, handover.planned_at_s + handover.lead_s

    def wait_in_job(self, ctx: JobContext, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Inside a job: block until predicate() holds (False after timeout_s of motion-clock time); raises
        JobCancelled on cancel or e-stop. In fast mode the physics advances meanwhile."""
        return self.wait_until(predicate, timeout_s, ctx)

    def run_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: check the trajectory (check_motion), command it (only while this job owns the arm)
        and wait for it."""
        trajectory = self.start_trajectory(ctx, trajectory)
        checked = ctx if not ctx.in_cleanup else None
        # a lower speed override set while it runs stretches it (retime_running): wait as long as the slowest speed takes
        if not self.wait_until(lambda: not self.arm.is_moving(), trajectory.duration_s * SPEED_WAIT_FACTOR + 5.0, checked):
            self.latch.halt_devices(gripper=False)
            if self.latch.is_set():
                raise JobCancelled("the station was e-stopped")
            raise TimeoutError(f"the arm did not finish a {trajectory.duration_s:.2f} s move in time")
        self.wait_until(lambda: arrived(self, trajectory.positions_rad[-1]), ARRIVE_TIMEOUT_S, checked)
        self.record.ended_now()
        if checked is not None:
            ctx.check()

    def settle_arm(self, ctx: JobContext) -> int:
        """Inside a job, before the arm's position is used (a grasp, a release, a sighting of the gripper): the real
        arm's unloaded joints still and corrected from their readings (settle.settle_at_rest); the corrections sent."""
        return settle_at_rest(self, ctx)

    def run_gripper(self, ctx: JobContext, action: str) -> None:
        """Inside a job: grasp or release (only while this job owns the arm; the arm settled first, settle_arm) and
        wait for the fingers."""
        if action not in ("grasp", "release"):
            raise InvalidInput(f"gripper action must be 'grasp' or 'release', not {action!r}")
        self.settle_arm(ctx)
        with self.sending():
            self._owns_arm(ctx)
            self.send_later(lambda: getattr(self.gripper, action)(wait=False))
        self.wait_gripper(ctx if not ctx.in_cleanup else None)

