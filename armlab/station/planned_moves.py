"""Plan, then execute (issue 22 item 2): a manual move planned and checked exactly as the real one would be, kept
(plans.PlanStore) and shown, moving nothing; Execute sends exactly that trajectory through the gate, or refuses.

A command object core.Station owns (station.planned; the station forwards its public methods), holding the kept plans
(plans.PlanStore). plan_only() refuses what the move would refuse (state, latch, lease, limits, the board,
the body and self-collision checks, reach, the start at the measured joints) and also a plan while the arm moves
(a plan starts from the arm at rest). execute_plan() refuses an unknown id (PlanNotFound), a plan executed already,
expired, or made before the arm or its world changed (PlanStale naming what changed), a plan another controller
made (PlanNotYours), and whatever the gate refuses any motion (state, latch, lease, the start): nothing moves then.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import ArmMoving, PlanNotYours, PlanStale
from armlab.motion.pick_place import TrajectoryStep
from armlab.motion.safety import check_start
from armlab.station.perception import DEVICE_ERRORS
from armlab.station.plans import PLAN_LIFETIME_S, MovePlan, PlanStore, new_plan_id
from armlab.station.states import allowed_commands
from armlab.station.telemetry import gripper_pose_from_matrix

PLAN_SHOWN_SAMPLES = 60  # at most this many samples of a plan's trajectory go on the wire (its ends included)
STALE_WHEN = (
    "executed once: a second execute is refused",
    f"expired {PLAN_LIFETIME_S:.0f} s after it was made",
    "the arm was commanded, halted or moved (by hand, by another client) since",
    "the scene, the camera calibration or the arm calibration changed since",
    "the gripper was opened or closed, or what it holds changed, since",
    "the speed override changed since",
)

# The world snapshot's entries, in order: (reason, what changed).
_WORLD = (
    ("arm_commanded", "the arm was commanded since the plan was made"),
    ("halted", "the arm was halted (e-stop, cancel or fault) since the plan was made"),
    ("scene_changed", "the scene changed since the plan was made (new objects, the camera or the board moved)"),
    ("calibration_changed", "the camera calibration changed since the plan was made"),
    ("calibration_changed", "the arm calibration changed since the plan was made"),
    ("gripper_changed", "what the gripper holds changed since the plan was made"),
    ("speed_changed", "the speed override changed since the plan was made"),
)


def world_change(before: tuple, now: tuple) -> tuple[str, str] | None:
    """(message, reason) of the first entry of two world snapshots that differs, else None."""
    for (reason, what), old, new in zip(_WORLD, before, now):
        if old is new or _equal(old, new):
            continue
        if reason == "speed_changed":
            what = f"the speed override changed from {old:g} % to {new:g} % since the plan was made"
        return f"the plan is stale: {what}; plan again", reason
    return None


def _equal(old, new) -> bool:
    try:
        return type(old) is type(new) and bool(old == new)
    except (TypeError, ValueError):  # values holding arrays: only the same object is the same
        return False


def joined(trajectories: Sequence[JointTrajectory]) -> JointTrajectory:
    """Trajectories run one after another as one (each starting where the one before ends; the shared sample once)."""
    times, positions, offset_s = [trajectories[0].times_s], [trajectories[0].positions_rad], trajectories[0].duration_s
    for trajectory in trajectories[1:]:
        times.append(offset_s + trajectory.times_s[1:])
        positions.append(trajectory.positions_rad[1:])
        offset_s += trajectory.duration_s
    return JointTrajectory(np.concatenate(times), np.vstack(positions))


def decimated_indices(count: int, most: int = PLAN_SHOWN_SAMPLES) -> np.ndarray:
    """At most `most` evenly spread sample indices of `count`, the first and last included."""
    if count <= most:
        return np.arange(count)
    return np.unique(np.round(np.linspace(0, count - 1, most)).astype(int))


class PlannedMoves:
    """plan_only, execute_plan, discard_plan and the plans' wire form. station: the core.Station that owns it."""

    def __init__(self, station) -> None:
        self._station = station
        self.plans = PlanStore()  # the plans made and not yet executed, discarded or expired

    def _world_snapshot(self) -> tuple:
        """What a plan depends on besides the arm's joints (in _WORLD's order), read under the lock."""
        station, gate = self._station, self._station.gate
        with station._lock:
            return (gate.command_count, station.latch.halts, gate.record.changed_everywhere_s, station.trust.calibration,
                    station.arm_calibration.info, station.held_block, gate.speed_percent)

    def _gripper_command(self) -> str | None:
        try:
            return self._station.gripper.read_state().command
        except DEVICE_ERRORS:
            return None

    def plan_only(self, command: str, q_goal_rad=None, moving_time_s: float | None = None, pose: tuple | None = None,
                  source: str | None = None) -> dict:
        """The move `command` (move_joints: q_goal_rad; move_to: pose = (position_m, pitch_rad, yaw_rad)) would make,
        planned and checked as the move itself, kept as a plan and returned in its wire form; nothing moves."""
        self._station.require_arm(command)
        self._station.allowed_or_raise(command, source)  # state, latch, lease: as the move would be refused, before any IK
        if pose is not None:
            q_goal_rad = self._station.solve_pose(*pose)
        self._station.checked_joints(q_goal_rad)
        context = self._plan_context(command, source)
        trajectory = self._station.gate.paced(self._station.plan_move(q_goal_rad, moving_time_s), context[2], from_rest=True)
        self._station.check_motion(trajectory)
        return self._kept_plan(command, source, trajectory, context)

    def plan_motion(self, command: str, make: Callable[[], JointTrajectory], source: str | None = None) -> dict:
        """A motion made by make() (planned and checked as the command makes it, e.g. a jog step) kept as a plan and
        returned in its wire form; nothing moves. The same refusals as plan_only before make() runs."""
        context = self._plan_context(command, source)
        trajectory = make()
        self._station.check_motion(trajectory)
        return self._kept_plan(command, source, trajectory, context)

    def plan_steps(self, command: str, steps: Sequence, start: Callable[[], object], source: str | None = None) -> dict:
        """A skill's motion (grab, drop: its TrajectoryStep / GripperStep as it would run them) kept as a plan and
        returned in its wire form; nothing moves. Each motion gets the full check the gate gives it (paced at the
        speed override, as the job would send it). Execute calls start(): the skill's job with exactly these steps."""
        context = self._plan_context(command, source)
        shown, goal = [], None
        for step in steps:
            if isinstance(step, TrajectoryStep):
                shown.append(self._station.gate.paced(step.trajectory, context[2], from_rest=True))
                self._station.check_motion(shown[-1])
            elif goal is None and shown:  # the gripper acts where the motion before it ends
                goal = shown[-1].positions_rad[-1].copy()
        if not shown:
            raise ValueError(f"{command}: the plan has no motion")
        return self._kept_plan(command, source, joined(shown), context, start=start, goal_rad=goal,
                               steps=tuple(step.name for step in steps))

    def plan_job(self, command: str, make: Callable[[], tuple], source: str | None = None) -> dict:
        """A job's motions planned and checked by the job's own planner at its own speed, kept as a plan and returned
        in its wire form; nothing moves. make() -> (its trajectories in order, the steps' names, start: the job
        running exactly them, started by Execute). The same refusals as plan_only before make() runs."""
        context = self._plan_context(command, source)
        trajectories, names, start = make()
        return self._kept_plan(command, source, joined(trajectories), context, start=start, steps=tuple(names))

    def _plan_context(self, command: str, source: str | None) -> tuple:
        """The refusals every plan gets (an arm, the state, latch and lease, the arm at rest), then what it depends
        on, read before it is planned: (world snapshot, the gripper's last command, the speed override)."""
        self._station.require_arm(command)
        self._station.allowed_or_raise(command, source)
        self._refuse_while_moving(command)
        return self._world_snapshot(), self._gripper_command(), self._station.speed_percent

    def _kept_plan(self, command: str, source: str | None, trajectory: JointTrajectory, context: tuple, **job) -> dict:
        """The checked trajectory kept as a plan from the measured joints (it must start there; job: a job's start,
        goal_rad and steps, see MovePlan); its wire form."""
        world, gripper_command, speed = context
        measured = self._station.joints_rad()
        check_start(trajectory, measured, self._station.motion_config.start_tolerance_rad, self._station.model.joint_names)
        plan = self.plans.add(MovePlan(new_plan_id(), command, source, trajectory, measured, gripper_command, world, speed,
                                       **job))
        return self.plan_wire(plan)

    def _arm_busy(self) -> bool:
        """The arm moves, or a motion sent to it has yet to end on the station's clock."""
        return self._station.arm.is_moving() or self._station.commanded_motion_running()

    def _refuse_while_moving(self, command: str) -> None:
        """ArmMoving: a plan starts from the arm at rest."""
        if self._arm_busy():
            state = self._station.state
            raise ArmMoving(command, state.value, allowed_commands(state),
                            "a plan starts from the arm at rest: plan again once it has stopped")

    def _refuse_if_stale(self, plan: MovePlan) -> None:
        """PlanStale when the plan expired, the arm is not where it was planned from, or the gripper changed
        (the world snapshot is compared under the lock, just before the send)."""
        if time.time() > plan.expires_s:
            raise PlanStale(f"the plan expired {time.time() - plan.expires_s:.0f} s ago (plans last "
                            f"{plan.lifetime_s:.0f} s): plan again", "expired")
        measured = self._station.joints_rad()
        error = np.abs(measured - plan.measured_rad)
        joint = int(np.argmax(error))
        if error[joint] > self._station.motion_config.start_tolerance_rad:
            raise PlanStale(f"the plan is stale: the arm moved since it was made ({self._station.model.joint_names[joint]} is "
                            f"{error[joint]:.3f} rad from where it was); plan again", "arm_moved")
        if self._gripper_command() != plan.gripper_command:
            raise PlanStale("the plan is stale: the gripper was opened or closed since the plan was made; plan again",
                            "gripper_changed")

    def execute_plan(self, plan_id: str, source: str | None = None):
        """Send exactly the plan's trajectory through the gate (state, lease, latch, start at the measured joints),
        or refuse with nothing moved. Returns what was sent; a skill's plan: the job started with its steps."""
        plan = self.plans.get(plan_id)
        if plan.executed:
            raise PlanStale(f"plan {plan_id!r} was executed already: plan again to move again", "executed")
        if source is not None and plan.controller != source:
            raise PlanNotYours(f"plan {plan_id!r} was made by {plan.controller or 'the station itself'!r}, not by "
                               f"{source!r}: each controller executes only its own plans; plan it again")
        self._station.allowed_or_raise(plan.command, source)
        self._refuse_if_stale(plan)
        if plan.start is not None:
            return self._start_planned_job(plan)
        claimed: list[bool] = []

        def send_as_planned(handover) -> JointTrajectory:
            # The world first: a move commanded since the plan, in its last still samples, is a handover at rest whose
            # position the plan does not start from (the splice would refuse it as a discontinuity, not as stale).
            change = world_change(plan.world, self._world_snapshot())
            if change is not None:
                raise PlanStale(*change)
            if handover is not None and not handover.at_rest:
                raise PlanStale("the plan is stale: the arm is moving; plan again once it has stopped", "arm_moving")
            return plan.trajectory

        def under_lock() -> None:
            change = world_change(plan.world, self._world_snapshot())
            if change is not None:
                raise PlanStale(*change)
            if not claimed:
                self.plans.claim(plan.plan_id)  # PlanStale 'executed' when another request just sent it
                claimed.append(True)
            self._station.gate.pace_next_send(plan.speed_percent)
            self._station._transition(plan.command, source=source)
            self._station._jog = None

        try:
            trajectory, _ = self._station.gate.send_replacing(send_as_planned, under_lock, plan.command, replaceable=True)
        except BaseException:
            if claimed:
                self.plans.unclaim(plan.plan_id)
            raise
        return trajectory

    def _start_planned_job(self, plan: MovePlan):
        """A skill's plan: refused stale as a motion's is (the world, the arm moving), else claimed and its job started."""
        change = world_change(plan.world, self._world_snapshot())
        if change is not None:
            raise PlanStale(*change)
        if self._arm_busy():
            raise PlanStale("the plan is stale: the arm is moving; plan again once it has stopped", "arm_moving")
        self.plans.claim(plan.plan_id)  # PlanStale 'executed' when another request just started it
        try:
            return plan.start()
        except BaseException:
            self.plans.unclaim(plan.plan_id)
            raise

    def discard_plan(self, plan_id: str, source: str | None = None) -> MovePlan:
        """Forget a plan (Cancel): PlanNotFound if unknown, PlanNotYours if another controller made it."""
        plan = self.plans.get(plan_id)
        if source is not None and plan.controller != source:
            raise PlanNotYours(f"plan {plan_id!r} was made by {plan.controller or 'the station itself'!r}, not by {source!r}")
        return self.plans.discard(plan_id)

    def plan_wire(self, plan: MovePlan) -> dict:
        """The plan as shown: its id, the trajectory (decimated), the gripper's path, the goal and when it goes stale."""
        trajectory = plan.trajectory
        index = decimated_indices(len(trajectory.times_s))
        q = trajectory.positions_rad[index]
        goal = trajectory.positions_rad[-1] if plan.goal_rad is None else plan.goal_rad
        path = np.asarray(self._station.model.fk(q), float)[:, :3, 3]
        base = np.asarray(self._station.model.T_world_base)[:3, 3]
        return {
            "plan_id": plan.plan_id, "command": plan.command, "controller": plan.controller,
            "goal_q_rad": [float(v) for v in goal], "duration_s": float(trajectory.duration_s),
            "times_s": [float(t) for t in trajectory.times_s[index]], "q_rad": q.tolist(),
            "gripper_path_m": path.tolist(), "gripper_pose": gripper_pose_from_matrix(self._station.model.fk(goal), base),
            "speed_percent": float(plan.speed_percent), "created_s": plan.created_s, "expires_s": plan.expires_s,
            "stale_when": list(STALE_WHEN), "steps": list(plan.steps),
        }
