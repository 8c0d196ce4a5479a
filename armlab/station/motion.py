"""The motion gate: waiting on the devices, sending trajectories, and the motion commands of jobs.

A mixin of core.Station. Every trajectory from any source (manual, jog, jobs) passes `check_motion`
(limits, velocity and acceleration, the table, the workspace box, the per-step jump) outside the lock and
`_command_arm` (latch, start at the measured joints) under it, inside `_sending()`, which sends to the
device once the lock is released (on the real arm a ROS service call: status and telemetry never wait for
it) and halts again if the latch went up meanwhile. Waits return at once when the latch is set
and, in fast mode, never let the physics run more than one control period past it.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import CommandRefused
from armlab.station.jobs import JobCancelled, JobContext
from armlab.station.states import JOB_STATES, allowed_commands

WAIT_CHUNK_S = 0.05  # waits on the devices check cancel/e-stop this often (simulated time in fast mode)
MOTION_MEMORY = 256  # how many recent arm motions the gate remembers for stale-perception checks


class MotionGate:
    """Waiting on the devices and sending motion."""

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
        from armlab.motion import check_trajectory

        config = self.motion_config
        # The table itself (no clearance): planners keep their own board_clearance_m; the straight joint-space
        # move from the sleep pose home passes the gripper point within 1 mm of the board.
        check_trajectory(self.model, trajectory, workspace_m=config.workspace_m, max_step_rad=config.max_step_rad)

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
                halts = self._halts
                self._outbox = outbox
                try:
                    yield
                finally:
                    self._outbox = None
            for send in outbox:
                send()
            if outbox and (self._halt.is_set() or self._halts != halts):
                self._halt_devices(gripper=self._halt.is_set())

    def _send_later(self, send: Callable[[], object]) -> None:
        """Queue a device command for when the lock is released (caller is inside `_sending()`)."""
        if self._outbox is None:
            raise RuntimeError("device commands are sent from inside Station._sending(), never under the bare lock")
        self._outbox.append(send)

    def _command_arm(self, trajectory: JointTrajectory, swept_box: np.ndarray) -> None:
        """Queue a checked trajectory for the arm and remember where the gripper sweeps. Caller is inside
        `_sending()` (holds the lock) and has checked the state; the latch and the start (no jump from the
        measured joints) are checked here; the trajectory reaches the arm once the lock is released."""
        from armlab.motion.safety import check_start

        if self._halt.is_set():
            raise CommandRefused("move", self._effective_state().value, allowed_commands(self._effective_state()))
        check_start(trajectory, self.joints_rad(), self.motion_config.start_tolerance_rad, self.model.joint_names)
        self._send_later(lambda: self.arm.command_trajectory(trajectory))
        self._motions.append((time.time() + trajectory.duration_s, swept_box))
        del self._motions[:-MOTION_MEMORY]

    def _swept_box(self, trajectory: JointTrajectory) -> np.ndarray:
        """[xmin, ymin, xmax, ymax] of the gripper point along a trajectory (sampled; no lock needed)."""
        positions = trajectory.positions_rad
        tips = self.model.fk(positions[:: max(1, len(positions) // 20)])[:, :2, 3]
        tips = np.vstack([tips, self.model.fk(positions[-1])[:2, 3]])
        return np.concatenate([tips.min(axis=0), tips.max(axis=0)])

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

    def start_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: check the trajectory (check_motion) and command it (only while this job owns the
        arm), without waiting; it replaces a motion in progress (it must start where the arm is)."""
        self.check_motion(trajectory)
        swept_box = self._swept_box(trajectory)
        with self._sending():
            self._owns_arm(ctx)
            self._command_arm(trajectory, swept_box)

    def wait_in_job(self, ctx: JobContext, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Inside a job: block until predicate() holds (False after timeout_s of motion-clock time); raises
        JobCancelled on cancel or e-stop. In fast mode the physics advances meanwhile."""
        return self._wait_until(predicate, timeout_s, ctx)

    def run_trajectory(self, ctx: JobContext, trajectory: JointTrajectory) -> None:
        """Inside a job: check the trajectory (check_motion), command it (only while this job owns the arm)
        and wait for it."""
        self.start_trajectory(ctx, trajectory)
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
        with self._sending():
            self._owns_arm(ctx)
            self._send_later(lambda: getattr(self.gripper, action)(wait=False))
        self.wait_gripper(ctx if not ctx.in_cleanup else None)

    def move_in_job(self, ctx: JobContext, q_goal_rad, moving_time_s: float | None = None) -> None:
        self.run_trajectory(ctx, self.plan_move(q_goal_rad, moving_time_s))
