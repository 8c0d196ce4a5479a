"""Manual commands of the gate: joint and pose moves, hold-to-run jog, torque, gripper (teach: teach.py).

A command object core.Station owns (station.manual; the station forwards its public methods): it holds the jog step's
anchor, records each command's state change through the station's `_transition` under its lock, and sends through the
gate (`sending`, `command_arm`, `send_replacing`). Every command is refused before planning (state, latch, lease),
planned and checked outside the lock, then re-checked and sent under it; nothing slow (IK, planning, SQLite) runs
while the lock is held.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PLAN_REFUSALS, ArmMoving, CommandRefused, InvalidInput, NeedsConfirmation, NotController
from armlab.motion import plan_joint_move
from armlab.motion.blend import arm_limits, plan_run
from armlab.motion.gripper_step import LINEAR_AXES, ORIENTATION_TOL_RAD, StepSpeeds, plan_gripper_step, yaw_turn_rad
from armlab.motion.jog import checked_jog_velocity, plan_jog
from armlab.motion.pose_path import holds_full_pose, solve_pose_move
from armlab.station.checks import checked_moving_time, checked_position
from armlab.station.job_control import SPEED_WAIT_FACTOR
from armlab.station.states import State, allowed_commands
from armlab.station.telemetry import gripper_pose_from_matrix

STEP_ANCHOR_TOL_RAD = 0.01  # a step starts from the previous step's commanded end when the arm is this close to it


class ManualCommands:
    """Operator commands outside jobs (idle and teach). station: the core.Station that owns it."""

    def __init__(self, station) -> None:
        self._station = station
        self._step_anchor: tuple | None = None  # the last jog step's commanded end and its motion record entry (step_gripper)

    def plan_move(self, q_goal_rad, moving_time_s: float | None = None) -> JointTrajectory:
        """A checked joint move from the current position (ValueError/UnsafeTrajectory: nothing moves)."""
        station = self._station
        q_goal = station.checked_joints(q_goal_rad)
        trajectory = plan_joint_move(
            station.start_position(), q_goal, station.model, moving_time_s=checked_moving_time(moving_time_s, station.config.max_moving_time_s)
        )
        self._station.check_motion(trajectory)
        return trajectory

    def plan_move_from(self, handover, q_goal_rad, moving_time_s: float | None = None) -> JointTrajectory:
        """A joint move to q_goal that takes over a running motion at `handover` (armlab.motion.handover): the
        synchronised trapezoid when the handover is at rest, else a jerk-limited blend (ruckig) from its
        position, velocity and acceleration within the arm's limits, ending at rest on the goal (moving_time_s:
        its least duration). ValueError when none can be planned. Not checked (the splice is)."""
        q_goal = self._station.checked_joints(q_goal_rad)
        moving_time = checked_moving_time(moving_time_s, self._station.config.max_moving_time_s)
        if handover.at_rest:
            return plan_joint_move(handover.position_rad, q_goal, self._station.model, moving_time_s=moving_time)
        run = plan_run(
            np.vstack([handover.position_rad, q_goal]), arm_limits(self._station.model),
            start_velocity=handover.velocity_rad_s, start_accel=handover.accel_rad_s2,
            minimum_s=[None, moving_time] if moving_time else None, rate_hz=self._station.motion_config.sample_rate_hz,
        )
        return run.trajectory

    def _manual_move(self, command: str, q_goal_rad, moving_time_s: float | None, wait: bool, source: str | None) -> None:
        """A manual joint move, planned and checked outside the lock; it takes over a motion in progress
        continuously (plan_move_from), else starts from the measured joints at rest."""
        self._station.allowed_or_raise(command, source)  # refuse before planning
        self._station.checked_joints(q_goal_rad)

        pace = {}  # the speed override it is planned at (the gate paces it)

        def plan(handover) -> JointTrajectory:
            pace["speed"] = self._station.speed_percent
            if handover is None:
                return self._station.gate.paced(self.plan_move(q_goal_rad, moving_time_s), pace["speed"], from_rest=True)
            return self._station.gate.paced(self.plan_move_from(handover, q_goal_rad, moving_time_s), pace["speed"], from_rest=handover.at_rest)

        def under_lock() -> None:
            self._station.gate.pace_next_send(pace["speed"])  # the override changed meanwhile: planned again
            self._station._transition(command, source=source)  # state unchanged: idle/teach stay
            self._station._jog = None

        trajectory, _ = self._station.gate.send_replacing(plan, under_lock, command, replaceable=True)
        if wait:
            self._station.wait_motion(trajectory.duration_s * SPEED_WAIT_FACTOR + 5.0)

    def move_in_job(self, ctx, q_goal_rad, moving_time_s: float | None = None) -> None:
        """Inside a job: a checked joint move from where the arm is (plan_move), run through the gate and waited for."""
        self._station.run_trajectory(ctx, self.plan_move(q_goal_rad, moving_time_s))

    def move_joints(self, q_rad, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._manual_move("move_joints", q_rad, moving_time_s, wait, source)

    def home(self, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._station.require_arm("home")
        self._manual_move("home", self._station.model.home_rad, moving_time_s, wait, source)

    def sleep(self, moving_time_s: float | None = None, wait: bool = False, source: str | None = None) -> None:
        self._station.require_arm("sleep")
        self._manual_move("sleep", self._station.model.sleep_rad, moving_time_s, wait, source)

    def solve_pose(self, position_m, pitch_rad: float | None = None, yaw_rad: float | None = None) -> np.ndarray:
        """IK for a world position (Unreachable, a ValueError, says why); validates the numbers first."""
        position = checked_position(position_m)
        for name, angle in (("pitch_rad", pitch_rad), ("yaw_rad", yaw_rad)):
            if angle is not None and not math.isfinite(float(angle)):
                raise InvalidInput(f"{name} must be finite")

        if holds_full_pose(self._station.model):  # six joints or more: a full pose (ik_pose), the tool's heading kept without a yaw
            return solve_pose_move(self._station.model, position, pitch_rad, yaw_rad, self._station.joints_rad())
        return self._station.model.ik(position, pitch=pitch_rad, yaw=yaw_rad, q_seed=self._station.joints_rad())

    def move_to(self, position_m, pitch_rad=None, yaw_rad=None, moving_time_s=None, wait=False, source=None) -> np.ndarray:
        """Move the gripper point to a world position (IK outside the lock, joint move); returns the goal joints."""
        self._station.allowed_or_raise("move_to", source)
        q_goal = self.solve_pose(position_m, pitch_rad, yaw_rad)
        self._manual_move("move_to", q_goal, moving_time_s, wait=False, source=source)
        if wait:
            self._station.wait_motion(self._station.config.max_moving_time_s * SPEED_WAIT_FACTOR + 5.0)
        return q_goal

    def check_move(self, q_goal_rad=None, moving_time_s: float | None = None, pose: tuple | None = None) -> dict:
        """What move_joints (q_goal_rad) or move_to (pose: (position_m, pitch_rad, yaw_rad)) would send, moving
        nothing: {q_rad, duration_s, gripper_pose} of the checked move from where the arm is now. The same refusals
        as the move (InvalidInput, Unreachable, UnsafeTrajectory with the reason); no state, latch or lease needed."""
        self._station.require_arm("move_to" if pose is not None else "move_joints")
        if pose is not None:
            q_goal_rad = self.solve_pose(*pose)
        trajectory = self.plan_move(q_goal_rad, moving_time_s)
        q_goal = trajectory.positions_rad[-1]
        base = np.asarray(self._station.model.T_world_base)[:3, 3]
        return {"q_rad": [float(v) for v in q_goal], "duration_s": float(trajectory.duration_s),
                "gripper_pose": gripper_pose_from_matrix(self._station.model.fk(q_goal), base)}

    def jog(self, velocity_rad_s, source: str | None = None, speed_percent: float = 100.0) -> JointTrajectory:
        """Hold-to-run: move at these joint velocities (rad/s, scaled by speed_percent) for motion jog_hold_s,
        then stop by itself. Sending it again (or heartbeat()) within jog_hold_s keeps it going; zeros ramp down to rest."""
        self._station.require_arm("jog")
        config = self._station.motion_config
        allowed = np.minimum(np.asarray(self._station.model.velocity_limit_rad_s, dtype=float), config.jog_max_speed_rad_s)
        velocity = checked_jog_velocity(velocity_rad_s, allowed, self._station.model.joint_names)
        velocity = velocity * checked_speed_percent(speed_percent) / 100.0
        self._station.allowed_or_raise("jog", source)

        def plan(handover) -> JointTrajectory:
            # It brakes jog_hold_s after this command: a plan taking over later holds the speed that much less.
            if handover is None:
                q0, v0, hold_s = self._station.start_position(), np.zeros_like(velocity), config.jog_hold_s
            else:
                q0, v0 = handover.position_rad, handover.segment_velocity_rad_s
                hold_s = max(config.jog_hold_s - (handover.takes_over_s - self._station.clock_s()), 1.0 / config.sample_rate_hz)
            return plan_jog(q0, v0, velocity, hold_s, self._station.model.lower_rad, self._station.model.upper_rad,
                            arm_limits(self._station.model).accel_rad_s2, config.sample_rate_hz)  # 2 % inside, as the blends

        trajectory, _ = self._station.gate.send_replacing(plan, lambda: self._station._transition("jog", source=source), "jog")
        with self._station._lock:
            self._station._jog = {"trajectory": trajectory, "start_s": self._station.clock_s(), "velocity": velocity, "source": source}
        return trajectory

    def step_gripper(
        self, axis: str, amount: float, speed_percent: float = 100.0, wait: bool = False, source: str | None = None,
        plan_only: bool = False,
    ) -> JointTrajectory | dict:
        """A jog step of the gripper: `amount` m along world x|y|z keeping its pitch and yaw, or rad of
        pitch|roll (armlab.motion.gripper_step), at speed_percent of the configured step speeds.

        Refused before anything moves: ArmMoving while the arm still moves, StepRefused/Unreachable (the
        reason) when the step cannot keep the gripper's orientation and line. A step that follows this
        station's previous step starts from that step's commanded end (the servos' sag does not add up).
        plan_only: the step planned from the measured joints and kept as a plan (its wire form); nothing moves."""
        scale = checked_speed_percent(speed_percent) / 100.0
        if plan_only:
            return self._station.plan_motion("jog", lambda: self._gripper_step(axis, amount, scale, self._station.joints_rad()), source)
        self._station.allowed_or_raise("jog", source)
        if self._station.arm.is_moving():
            raise ArmMoving("jog", self._station.state.value, allowed_commands(self._station.state))
        q_start = self._station.joints_rad()
        with self._station._lock:  # the anchor holds while no other motion was commanded since (nor halted: that replaces the entry)
            anchor = self._step_anchor
            last_motion = self._station.gate.record.last()
        if anchor is not None and anchor[1] is last_motion and np.max(np.abs(anchor[0] - q_start)) <= STEP_ANCHOR_TOL_RAD:
            q_start = anchor[0]
        trajectory = self._gripper_step(axis, amount, scale, q_start)
        self._station.check_motion(trajectory)
        swept_box = self._station.gate.record.swept_box(trajectory)
        with self._station.gate.sending():
            self._station._transition("jog", source=source)
            self._station._jog = None
            self._station.gate.command_arm(trajectory, swept_box)
            self._step_anchor = (trajectory.positions_rad[-1].copy(), self._station.gate.record.last())
        if axis in LINEAR_AXES and abs(turn := yaw_turn_rad(self._station.model, trajectory.positions_rad)) > ORIENTATION_TOL_RAD:
            self._station.events.add("info", f"{axis} step: the gripper's yaw turned {math.degrees(turn):+.1f}° with the waist (a 5-joint arm "
                                    "holds its heading only pointing down)")
        if wait:
            self._station.wait_motion(trajectory.duration_s + 5.0)
        return trajectory

    def _gripper_step(self, axis: str, amount: float, scale: float, q_start: np.ndarray) -> JointTrajectory:
        """The step's trajectory from q_start at `scale` of the configured step speeds (StepRefused/Unreachable)."""
        config = self._station.motion_config
        speeds = StepSpeeds(
            config.step_speed_m_s * scale, config.step_accel_m_s2 * scale,
            config.step_rotation_speed_rad_s * scale, config.step_rotation_accel_rad_s2 * scale,
        )
        return plan_gripper_step(self._station.model, q_start, axis, amount, speeds, self._station.finger_box(), config.board_clearance_m,
                                 config.sample_rate_hz)

    def heartbeat(self, source: str | None = None) -> bool:
        """The controlling client is still there: extend its running jog by jog_hold_s. False (nothing
        moves) when it has no jog running or the jog may not go on (e-stop, another controller, a limit)."""
        return self._reissue_jog(source, stop=False)

    def _reissue_jog(self, source: str | None, stop: bool) -> bool:
        """Send `source`'s running hold-to-run jog again, joint or Cartesian (cartesian_jog.py): at its velocity (held
        on for jog_hold_s) or, stop=True, at zero (ramping down now). False when it has none running or it may not go
        on (e-stop, another controller, a limit): then it runs out by itself."""
        with self._station._lock:
            jog = self._station._jog
        if jog is None or jog["source"] != source or not self._station.arm.is_moving():
            return False
        try:
            if "axis" in jog:
                self._station.jog_cartesian(jog["axis"], 0.0 if stop else jog["velocity"], source=source)
            else:
                self.jog(np.zeros(len(jog["velocity"])) if stop else jog["velocity"], source=source)
        except (CommandRefused, NotController, *PLAN_REFUSALS):
            return False
        return True

    def set_torque(self, enabled: bool, source: str | None = None, confirm: bool = False) -> None:
        """Torque on, or off (limp: the arm falls under gravity unless held), which outside teach needs
        confirm=True (NeedsConfirmation otherwise: nothing changes)."""
        with self._station.gate.sending():  # the torque call (a ROS service on the real arm) is made after the lock is released
            state = self._station._check("torque", source)
            if not enabled and state is not State.TEACH and not confirm:
                raise NeedsConfirmation(
                    "torque off outside teach lets the arm fall under gravity: hold the arm and send confirm: true "
                    "(or start teach first)"
                )
            self._station._transition("torque", source=source)
            self._station._jog = None
            if self._station.latch.is_set():
                raise CommandRefused("torque", self._station._effective_state().value, allowed_commands(self._station._effective_state()))
            self._station.gate.send_later(lambda: self._station.arm.set_torque(bool(enabled)))
        with self._station._lock:
            self._station.gate.forget_commanded()
            self._station._torque_enabled = bool(enabled)
        self._station.events.add("warn" if not enabled else "info", f"torque {'on' if enabled else 'off'}")

    def gripper_command(self, action: str, wait: bool = True, source: str | None = None) -> None:
        """'grasp' or 'release'."""
        if action not in ("grasp", "release"):
            raise InvalidInput(f"gripper action must be 'grasp' or 'release', not {action!r}")
        with self._station.gate.sending():
            self._station._transition("gripper", source=source)
            self._station.gate.send_later(lambda: getattr(self._station.gripper, action)(wait=False))
        self._station.note_gripper_change()  # what is under the gripper may change (a block let go): remembered depth there is stale
        if wait:
            self._station.wait_gripper()


def checked_speed_percent(speed_percent) -> float:
    """The operator's speed override as a finite number in [10, 100] %, else ValueError."""
    try:
        value = float(speed_percent)
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"speed_percent must be a number from 10 to 100, got {speed_percent!r}") from error
    if not (math.isfinite(value) and 10.0 <= value <= 100.0):
        raise InvalidInput(f"speed_percent must be from 10 to 100, got {speed_percent!r}")
    return value
