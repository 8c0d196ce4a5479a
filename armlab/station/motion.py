"""The motion gate: waiting on the devices, sending trajectories, and the motion commands of jobs.

A mixin of core.Station. Every trajectory from any source (manual, jog, jobs) passes `check_motion`
(limits, velocity and acceleration, the table, the workspace box, the per-step jump) outside the lock and
`_command_arm` (latch, start at the measured joints) under it, inside `_sending()`, which sends to the
device once the lock is released (on the real arm a ROS service call: status and telemetry never wait for
it) and halts again if the latch went up meanwhile. Waits return at once when the latch is set
and, in fast mode, never let the physics run more than one control period past it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PLAN_REFUSALS, ArmMoving, CommandRefused, InvalidInput
from armlab.motion import check_trajectory
from armlab.motion.blend import arm_limits, plan_stop
from armlab.motion.clearance import self_collision
from armlab.motion.handover import Handover, continuity_problem, reference_velocity, splice, take_over, trimmed
from armlab.motion.safety import UnsafeTrajectory, check_start
from armlab.station.arm_info import station_end_effector
from armlab.station.body_check import check_parts_above_board, palm_corners_m
from armlab.station.job_control import SPEED_WAIT_FACTOR
from armlab.station.jobs import JobCancelled, JobContext
from armlab.station.settle import ARRIVE_TIMEOUT_S, arrived, settle_at_rest
from armlab.station.states import JOB_STATES, allowed_commands

WAIT_CHUNK_S = 0.05  # waits on the devices check cancel/e-stop this often (simulated time in fast mode)
CHANGE_ABOVE_M = 0.06  # the gripper point this close above a spot's surface can have changed it (fingers, a held block)
MOTION_MEMORY = 256  # how many recent arm motions the gate remembers for stale-perception checks


class HandoverLate(RuntimeError):
    """A planned handover can no longer be used (its moment passed, or another motion was commanded): plan again."""


class MotionGate:
    """Waiting on the devices and sending motion."""

    def _wait_until(self, predicate: Callable[[], bool], timeout_s: float, ctx: JobContext | None = None) -> bool:
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
        return self._wait_until(lambda: not self.arm.is_moving(), timeout_s)

    def wait_gripper(self, ctx: JobContext | None = None) -> None:
        """Wait until the fingers stop moving (≤ gripper_settle_timeout_s of motion-clock time)."""
        self._wait_until(self.fingers_still_check(), self.config.gripper_settle_timeout_s, ctx)

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


    def check_motion(self, trajectory: JointTrajectory) -> None:
        """The full safety check of a trajectory (UnsafeTrajectory says why): joint, velocity and
        acceleration limits, the table, the workspace box, the per-step jump. No lock needed (pure)."""
        config = self.motion_config
        # The table itself (no clearance): planners keep their own board_clearance_m; the straight joint-space
        # move from the sleep pose home passes the gripper point within 1 mm of the board.
        check_trajectory(self.model, trajectory, workspace_m=config.workspace_m, max_step_rad=config.max_step_rad)
        self.check_body(trajectory)

    def check_pose(self, q_rad) -> np.ndarray:
        """The arm standing at q_rad passes the trajectory check (limits, the table, the workspace box, the fingers
        against the board, the arm against itself): returns the joints; ValueError / UnsafeTrajectory say why."""
        q = self.checked_joints(q_rad)
        self.check_motion(JointTrajectory(np.array([0.0, 0.01]), np.vstack([q, q])))
        return q

    def check_poses(self, poses_rad) -> None:
        """check_pose of every pose, the error naming the 1-based waypoint (programs, drafts)."""
        for index, q in enumerate(poses_rad, start=1):
            try:
                self.check_pose(q)
            except UnsafeTrajectory as error:
                raise UnsafeTrajectory(f"waypoint {index}: {error}") from None
            except InvalidInput as error:
                raise InvalidInput(f"waypoint {index}: {error}") from None

    @contextmanager
    def _sending(self) -> Iterator[None]:
        """`with self._sending():` instead of `with self._lock:` around checks that end in device commands: the
        body runs under the lock and queues its commands (_send_later), which are sent after the lock is
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

    def _send_later(self, send: Callable[[], object]) -> None:
        """Queue a device command for when the lock is released (caller is inside `_sending()`)."""
        if self._outbox is None:
            raise RuntimeError("device commands are sent from inside Station._sending(), never under the bare lock")
        self._outbox.append(send)

    def check_body(self, trajectory: JointTrajectory) -> None:
        """UnsafeTrajectory (with the reason and when) if the fingers (a box around them, or the suction cup's
        body) go into the board, or the gripper end of the arm (gripper point, finger tips, the held block) into
        the arm's own base or upper arm, at any sample (armlab.motion.clearance). No lock needed (pure)."""
        config, positions, times = self.motion_config, trajectory.positions_rad, trajectory.times_s
        parts = {"fingers": self.finger_box().corners_m()}
        if (palm := self.palm_corners_m()) is not None:
            parts["palm"] = palm
        check_parts_above_board(self.model, positions, times, parts)
        held = self.held_block
        held_edge_m = float(held["edge_m"]) if held and held.get("edge_m") else None
        hit = self_collision(self.model, positions, base_radius_m=config.base_radius_m, reach_m=config.self_clearance_m,
                             held_edge_m=held_edge_m)
        if hit is not None:
            sample, part, what = hit
            raise UnsafeTrajectory(f"{what} at t = {times[sample]:.3f} s: the arm would hit itself", part=part,
                                   at_q_rad=positions[sample])

    def palm_corners_m(self) -> np.ndarray | None:
        """(8, 3) corners of a finger gripper's palm in the gripper frame; None for a suction cup."""
        return palm_corners_m(self.model.config.name) if station_end_effector(self).has_palm else None

    def finger_box(self):
        """The box the gripper occupies beyond the wrist (armlab.motion.gripper_step.FingerBox): the open fingers
        from config, or the suction cup's body."""
        return station_end_effector(self).body_box(self.motion_config, self.model.config)

    def _command_arm(self, trajectory: JointTrajectory, swept_box: np.ndarray, handover: Handover | None = None,
                     planned_after: int | None = None) -> JointTrajectory:
        """Send a checked trajectory and remember it and where the gripper sweeps; returns what was sent.
        Caller is inside `_sending()` (holds the lock; the trajectory reaches the arm once the lock is released)
        and has checked the state; checked here: the latch, the start (no jump from the
        measured joints) and, while a commanded motion runs, that this one continues it: a splice from
        `handover` (taken from that very motion; trimmed to now: HandoverLate when now is past the handover)
        or a trajectory starting at the running reference and its velocity (ArmMoving otherwise). Either is sent
        with its start on the arm's clock (Arm.command_trajectory's start_time_s: the station's clock is the arm's),
        so a send held up after the check still continues the running curve; a motion from rest starts when the
        arm takes it, and the record follows (_started_at)."""
        state = self._effective_state()
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
            slow_rad_s = np.asarray(self.model.accel_limit_rad_s2, float) / self.motion_config.sample_rate_hz
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
        self._paced_motion, self._pace_next = (planned, self._pace_next), None  # speed.py: what a change re-times
        if handover is not None:  # the arm samples the splice at its own clock minus this: a late send continues it
            start_s = handover.planned_at_s + max(elapsed, 0.0)  # (before 0: a motion from rest not begun yet, as it will)
            self._send_later(lambda: self.arm.command_trajectory(trajectory, start_time_s=start_s))
        elif continues:  # it starts at the running reference now: the same, from now
            self._send_later(lambda: self.arm.command_trajectory(trajectory, start_time_s=now))
        else:  # from rest: a late send starts late without a jump, and the record follows the arm's start
            self._send_later(lambda: self._started_at(record, self.arm.command_trajectory(trajectory)))
        self._motions.append((time.time() + trajectory.duration_s, swept_box))
        del self._motions[:-MOTION_MEMORY]
        return trajectory

    def _check_start(self, trajectory: JointTrajectory, measured: np.ndarray) -> None:
        """UnsafeTrajectory unless the trajectory starts within start_tolerance_rad of the readings or of the command
        holding the arm there (model.command_holding): a step chained from the last one's commanded end starts at the
        latter, the real RX200's readings 0.04-0.05 rad below it at far reach (its servos' steady error)."""
        tolerance, names = self.motion_config.start_tolerance_rad, self.model.joint_names
        try:
            check_start(trajectory, measured, tolerance, names)
        except UnsafeTrajectory:
            command = self._holding_command(measured)
            if np.abs(command - measured).max() < 1e-9:
                raise
            check_start(trajectory, command, tolerance, names)

    def _holding_command(self, q_read) -> np.ndarray:
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
        with self._lock:
            last_motion_end_s = self._motions[-1][0] if self._motions else -math.inf
        if time.time() < last_motion_end_s:
            return "the arm is moving"
        try:
            joint_state = self.arm.read_joint_state()
            speed = np.abs(np.asarray(joint_state.velocity_rad_s, dtype=float))
            if self.arm.is_moving() or (speed.size and speed.max() > self.config.moving_speed_rad_s):
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
        if running[0].duration_s - (self.clock_s() - running[1]) > 2.0 / self.motion_config.sample_rate_hz:
            return measured
        held = running[0].positions_rad[-1]
        command = self._holding_command(measured)  # the servos' steady error taken off
        if float(np.max(np.abs(held - command))) > 0.5 * self.motion_config.start_tolerance_rad:
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
        config = self.motion_config
        lead = config.handover_lead_s if lead_s is None else lead_s
        return take_over(running[0], running[1], self.clock_s(), lead, config.sample_rate_hz, running[2])

    def _send_replacing(self, plan: Callable, under_lock: Callable[[], None] | None = None, command: str = "move",
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
        lead = self.motion_config.handover_lead_s
        if replaceable:
            with self._lock:
                self._newest_move += 1
                ticket = self._newest_move
        with self._plan_lock:
            with self._lock:
                state = self._effective_state()
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
                self.check_motion(trajectory)
                swept_box = self._swept_box(trajectory)
                try:
                    with self._sending():
                        if under_lock is not None:
                            under_lock()
                        self._command_arm(trajectory, swept_box, handover, planned_after=seen)
                    return trajectory, handover
                except HandoverLate:
                    lead *= 2.0
        state = self.state
        raise ArmMoving(command, state.value, allowed_commands(state), "planning could not keep up with the motion in progress")

    def brake_to_rest(self, ctx: JobContext | None = None) -> None:
        """Bring a motion in progress to rest on a jerk-limited stop at the arm's limits (no-op at rest), and
        wait until the arm stands still. Inside a job only while the job owns the arm."""
        handover = self.motion_handover()
        if handover is None and not self.arm.is_moving():
            return
        if handover is not None and not handover.at_rest:
            limits = arm_limits(self.model)
            rate = self.motion_config.sample_rate_hz

            def stop(handover: Handover | None) -> JointTrajectory:
                if handover is None:
                    raise HandoverLate("the motion ended meanwhile")
                return plan_stop(handover.position_rad, handover.velocity_rad_s, handover.accel_rad_s2, limits, rate)

            owns = (lambda: self._owns_arm(ctx)) if ctx is not None else None
            try:
                self._send_replacing(stop, owns, "stop")
            except (HandoverLate, *PLAN_REFUSALS):  # the motion ended meanwhile, or the stop fails its check: it runs out
                pass
        self._wait_until(lambda: not self.arm.is_moving(), 30.0, ctx)

    def _swept_box(self, trajectory: JointTrajectory) -> np.ndarray:
        """[xmin, ymin, xmax, ymax] of the gripper point along a trajectory, then the sampled points' x, y, z
        (for changed_at_since; sampled, no lock needed)."""
        positions = trajectory.positions_rad
        tips = self.model.fk(positions[:: max(1, len(positions) // 40)])[:, :3, 3]
        tips = np.vstack([tips, self.model.fk(positions[-1])[:3, 3]])
        return np.concatenate([tips[:, :2].min(axis=0), tips[:, :2].max(axis=0), tips.ravel()])

    def _owns_arm(self, ctx: JobContext) -> None:
        """Inside a job, under the lock: JobCancelled unless this job may still command the devices
        (it is current and not cancelled, or it is running its cleanup after a cancel), and never
        once the latch is set."""
        if self._job is not ctx.job or self._state not in JOB_STATES or self.latch.is_set():
            raise JobCancelled("job is no longer current")
        if not ctx.in_cleanup:
            ctx.check()

    def moved_over_since(self, point_m, since_s: float, radius_m: float = 0.06) -> bool:
        """True if a motion that ended after `since_s` (wall time, like frame timestamps) swept the gripper
        within radius_m of point_m in x-y: a detection seen at since_s may be stale there."""
        x, y = float(point_m[0]), float(point_m[1])
        with self._lock:
            motions = list(self._motions)
        for end_s, box in motions:
            xmin, ymin, xmax, ymax = box[:4]
            if end_s > since_s and xmin - radius_m <= x <= xmax + radius_m and ymin - radius_m <= y <= ymax + radius_m:
                return True
        return False

    def changed_at_since(self, point_m, since_s: float, radius_m: float = 0.06, above_m: float = CHANGE_ABOVE_M) -> bool:
        """True if after `since_s` the gripper came down within above_m of point_m's height within radius_m of it
        in x-y (a motion through the spot, a drop or a grab there, a gripper opened or closed over it), or a change
        everywhere was noted (note_change_everywhere): what was seen there at since_s may have changed."""
        spot = np.asarray(point_m[:3], float)
        with self._lock:
            if self._changed_everywhere_s > since_s:
                return True
            motions = list(self._motions)
        for end_s, box in motions:
            points = np.asarray(box[4:], float).reshape(-1, 3)  # the gripper's sampled path
            if end_s > since_s and np.any((np.linalg.norm(points[:, :2] - spot[:2], axis=1) <= radius_m) & (points[:, 2] < spot[2] + above_m)):
                return True
        return False

    def note_change_everywhere(self) -> None:
        """A change that may have changed any spot (a new scene, a checkerboard held up or put away, the camera
        knocked): for changed_at_since, what was seen before it and is hidden since is unknown everywhere."""
        with self._lock:
            self._changed_everywhere_s = time.time()

    def note_gripper_change(self) -> None:
        """A grasp or release where the gripper is: a change there for changed_at_since (no motion of the arm)."""
        if self.model is None:
            return
        try:
            point = np.asarray(self.model.fk(self.joints_rad()), float)[:3, 3]
        except (ConnectionError, TimeoutError, OSError):  # the arm not answering: its own fault path reports that
            return
        with self._lock:
            # whatever it held falls straight down: every spot below the gripper may have changed
            self._motions.append((time.time(), np.array([point[0], point[1], point[0], point[1], point[0], point[1], -np.inf])))
            del self._motions[:-MOTION_MEMORY]

    def start_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> JointTrajectory:
        """Inside a job: check the trajectory (check_motion) and command it (only while this job owns the
        arm), without waiting; while a motion runs it must continue it (replace_trajectory plans one that does).
        Paced at the speed override (speed.py) unless the job paces itself (a repeat's RunControl). Returns
        what was sent."""
        paces = getattr(ctx.job, "control", None) is None
        with self._speed_lock:  # a change of the override waits for this send, then re-times it
            speed = self.speed_percent
            if paces:
                trajectory = self._paced(trajectory, speed)
            self.check_motion(trajectory)
            swept_box = self._swept_box(trajectory)
            with self._sending():
                self._owns_arm(ctx)
                if paces:
                    self._pace_next_send(speed)
                self._command_arm(trajectory, swept_box)
        return trajectory

    def replace_trajectory(self, ctx: JobContext, plan: Callable) -> tuple[JointTrajectory, float, float]:
        """Inside a job: replace the motion in progress by plan(handover) (see _send_replacing), continuously.
        Returns (the command as spliced, the clock time of its t = 0, the clock time the new plan starts).
        ValueError / UnsafeTrajectory when the plan cannot be made or fails the check: nothing changes, the
        motion in progress goes on."""
        trajectory, handover = self._send_replacing(plan, lambda: self._owns_arm(ctx))
        if handover is None:
            start = self._commanded[1]
            return trajectory, start, start
        return trajectory, handover.planned_at_s, handover.planned_at_s + handover.lead_s

    def wait_in_job(self, ctx: JobContext, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Inside a job: block until predicate() holds (False after timeout_s of motion-clock time); raises
        JobCancelled on cancel or e-stop. In fast mode the physics advances meanwhile."""
        return self._wait_until(predicate, timeout_s, ctx)

    def run_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: check the trajectory (check_motion), command it (only while this job owns the arm)
        and wait for it."""
        trajectory = self.start_trajectory(ctx, trajectory)
        checked = ctx if not ctx.in_cleanup else None
        # a lower speed override set while it runs stretches it (speed.py): wait as long as the slowest speed takes
        if not self._wait_until(lambda: not self.arm.is_moving(), trajectory.duration_s * SPEED_WAIT_FACTOR + 5.0, checked):
            self.latch.halt_devices(gripper=False)
            if self.latch.is_set():
                raise JobCancelled("the station was e-stopped")
            raise TimeoutError(f"the arm did not finish a {trajectory.duration_s:.2f} s move in time")
        self._wait_until(lambda: arrived(self, trajectory.positions_rad[-1]), ARRIVE_TIMEOUT_S, checked)
        with self._lock:
            self._motions[-1] = (time.time(), self._motions[-1][1])
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
        with self._sending():
            self._owns_arm(ctx)
            self._send_later(lambda: getattr(self.gripper, action)(wait=False))
        self.wait_gripper(ctx if not ctx.in_cleanup else None)

    def move_in_job(self, ctx: JobContext, q_goal_rad, moving_time_s: float | None = None) -> None:
        self.run_trajectory(ctx, self.plan_move(q_goal_rad, moving_time_s))
