"""Pick and place plans: above → straight down → close/open → straight up, every trajectory checked.

A plan is a list of steps the station executes in order: TrajectoryStep (send to the arm, wait) or
GripperStep (grasp/release, wait). Heights come from MotionConfig (config/motion.yaml). The gripper
pitch is top-down when the whole approach is reachable that way, else the steepest pitch (in 5°
steps) that reaches the grasp, approach and lift points alike, so the vertical segments keep one
pitch. A suction cup (gripper_type "suction") only works flat on the top face: it approaches straight
down along its axis (top-down pitch only, no tilted fallback) onto the top face's centre, pressing
suction_press_m into the seal, with no grasp depth or finger width involved; an arm with six joints
or more holds the tool's whole orientation along the straight segments (armlab.motion.pose_path).
Pure: no device calls; armlab.kinematics.Unreachable when no pitch works.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.kinematics import Unreachable
from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.end_effector import FINGERS, EndEffector, end_effector
from armlab.motion.safety import check_trajectory
from armlab.motion.trajectory import plan_joint_move
from armlab.motion_config import MotionConfig

PITCH_STEP_RAD = math.radians(5.0)


@dataclass(frozen=True)
class TrajectoryStep:
    """Track `trajectory` with the arm; `name` says what the step is for ("move above", "descend", ...)."""

    name: str
    trajectory: JointTrajectory

    @property
    def q_end_rad(self) -> np.ndarray:
        return self.trajectory.positions_rad[-1]


@dataclass(frozen=True)
class GripperStep:
    """Gripper action: "grasp" closes on the block, "release" opens fully."""

    name: str
    action: Literal["grasp", "release"]


Step = TrajectoryStep | GripperStep


def _check_point(name: str, position_m) -> np.ndarray:
    position = np.asarray(position_m, dtype=float)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        raise InvalidInput(f"{name} must be 3 finite coordinates in metres, got {np.asarray(position_m).tolist()}")
    return position


def _check_finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise InvalidInput(f"{name} must be finite, got {value}")
    return value


def _pitch_candidates(preferred_rad: float, lowest_rad: float = 0.0) -> list[float]:
    count = int(math.floor((preferred_rad - lowest_rad) / PITCH_STEP_RAD + 1e-9))
    return [preferred_rad - k * PITCH_STEP_RAD for k in range(max(count, 0) + 1)]


def solve_approach(arm, q_seed_rad, points_m: list[np.ndarray], yaw_rad: float | None, preferred_pitch_rad: float,
                   lowest_pitch_rad: float = 0.0):
    """(pitch, [q per point]) for the steepest pitch ≤ preferred (and ≥ lowest) at which IK reaches every point.

    Points are solved in order, each seeded with the previous solution (so they share an IK branch).
    Raises Unreachable (from armlab.kinematics) with the first point's failure at the preferred pitch.
    """
    first_error = None
    for pitch in _pitch_candidates(preferred_pitch_rad, lowest_pitch_rad):
        seed = np.asarray(q_seed_rad, float)
        solutions = []
        try:
            for point in points_m:
                seed = np.asarray(arm.ik(point, pitch=pitch, yaw=yaw_rad, q_seed=seed), float)
                solutions.append(seed)
        except Unreachable as error:
            first_error = first_error or error
            continue
        return pitch, solutions
    pitches = (f"the gripper at {math.degrees(preferred_pitch_rad):.0f}° pitch (a suction cup seals only flat on a face) does not reach "
               if lowest_pitch_rad >= preferred_pitch_rad - 1e-9 else
               f"no gripper pitch between {math.degrees(preferred_pitch_rad):.0f}° and {math.degrees(lowest_pitch_rad):.0f}° reaches ")
    raise Unreachable(
        pitches + f"{', '.join(f'({p[0] * 1000:.0f}, {p[1] * 1000:.0f}, {p[2] * 1000:.0f}) mm' for p in points_m)}: {first_error}",
        getattr(first_error, "reason", "out of reach"),
    )


def _approach_steps(
    arm,
    q_now_rad,
    point_m: np.ndarray,
    yaw_rad: float,
    config: MotionConfig,
    action: Literal["grasp", "release"],
    words: tuple[str, str, str],
    tool: EndEffector = FINGERS,
    q_seed_rad=None,
) -> list[Step]:
    """Move above point_m, descend to it, do `action`, lift; all trajectories checked. q_seed_rad: the IK seed
    (default q_now): its last joint picks which of the equivalent finger headings the approach takes."""
    above_m = point_m + np.array([0.0, 0.0, config.approach_height_m])
    lift_m = point_m + np.array([0.0, 0.0, config.lift_height_m])
    # Solving the low point first fixes the pitch and IK branch; the descent itself reaches it.
    seed = q_now_rad if q_seed_rad is None else q_seed_rad
    pitch, (_q_point, q_above, _q_lift) = solve_approach(
        arm, seed, [point_m, above_m, lift_m], yaw_rad, config.top_down_pitch_rad, tool.lowest_pitch_rad(config)
    )
    vertical = dict(pitch_rad=pitch, yaw_rad=yaw_rad, speed_m_s=config.vertical_speed_m_s,
                    accel_m_s2=config.vertical_accel_m_s2, rate_hz=config.sample_rate_hz)
    move_above = plan_joint_move(q_now_rad, q_above, arm, config.move_time_s, config.accel_time_s, config.sample_rate_hz)
    descend = plan_vertical_segment(arm, q_above, float(point_m[2]), **vertical)
    lift = plan_vertical_segment(arm, descend.positions_rad[-1], float(lift_m[2]), **vertical)
    steps: list[Step] = [
        TrajectoryStep(words[0], move_above),
        TrajectoryStep(words[1], descend),
        GripperStep(action, action),
        TrajectoryStep(words[2], lift),
    ]
    for step in steps:
        if isinstance(step, TrajectoryStep):
            check_trajectory(arm, step.trajectory, clearance_m=config.board_clearance_m)
    return steps


def plan_pick(
    arm, q_now_rad, position_m, yaw_rad: float, config: MotionConfig, block_height_m: float | None = None,
    tool: EndEffector | str = FINGERS, q_seed_rad=None,
) -> list[Step]:
    """Steps to pick the block whose top-face centre is position_m (world, metres) with yaw yaw_rad.

    Open the gripper, move above the block (approach_height_m over the grasp point), go straight down
    to grasp_depth_for(block_height_m) below the top face (pads clear of what it stands on), grasp,
    go straight up lift_height_m. The grasp point is never lower than board_clearance_m. A suction cup
    goes straight down along its axis (pointing down) onto the top face centre, suction_press_m into
    it, and "grasp" turns the vacuum on ("release": off). tool: the end effector (or its type name).
    """
    tool = end_effector(tool)
    top_m = _check_point("position_m", position_m)
    yaw = _check_finite("yaw_rad", yaw_rad)
    height = math.inf  # unknown: as deep as the tool holds any block
    if block_height_m is not None:
        height = _check_finite("block_height_m", block_height_m)
        if height <= 0.0:
            raise InvalidInput(f"block_height_m must be > 0, got {height}")
    grasp_m = top_m - np.array([0.0, 0.0, tool.held_below_top_m(config, height)])
    grasp_m[2] = max(grasp_m[2], config.board_clearance_m, tool.lowest_grasp_m(config))
    steps = _approach_steps(arm, q_now_rad, grasp_m, yaw, config, "grasp", ("move above block", "descend to grasp", "lift"),
                            tool, q_seed_rad)
    return [GripperStep(tool.release_before_pick, "release"), *steps]


def plan_place(
    arm, q_now_rad, position_m, yaw_rad: float, config: MotionConfig, block_height_m: float, tool: EndEffector | str = FINGERS,
    q_seed_rad=None,
) -> list[Step]:
    """Steps to set the held block down with its bottom-face centre at position_m (world, metres).

    position_m is the surface point (board or the top of a stack). The gripper point, which holds the
    block grasp_depth_for(block_height_m) below its top (as plan_pick grasps), is released
    place_clearance_m above the resting height.
    """
    surface_m = _check_point("position_m", position_m)
    yaw = _check_finite("yaw_rad", yaw_rad)
    height = _check_finite("block_height_m", block_height_m)
    if height <= 0.0:
        raise InvalidInput(f"block_height_m must be > 0, got {height}")
    tool = end_effector(tool)
    held_below_top_m = tool.held_below_top_m(config, height)  # as plan_pick grasped it
    release_m = surface_m + np.array([0.0, 0.0, height - held_below_top_m + config.place_clearance_m])
    release_m[2] = max(release_m[2], config.board_clearance_m)
    return _approach_steps(arm, q_now_rad, release_m, yaw, config, "release", ("move above place", "descend to place", "retreat"),
                           tool, q_seed_rad)


def plan_move_to_pose(
    arm,
    q_now_rad,
    position_m,
    pitch_rad: float | None = None,
    yaw_rad: float | None = None,
    moving_time_s: float | None = None,
    accel_time_s: float | None = None,
    clearance_m: float = 0.0,
    rate_hz: float = 100.0,
) -> JointTrajectory:
    """A checked joint move to the gripper pose (position_m, pitch, yaw); IK seeded with q_now.

    Raises Unreachable (no IK solution), ValueError (bad input) or UnsafeTrajectory (the move would
    leave a limit or pass below the board + clearance_m).
    """
    target = _check_point("position_m", position_m)
    pitch = None if pitch_rad is None else _check_finite("pitch_rad", pitch_rad)
    yaw = None if yaw_rad is None else _check_finite("yaw_rad", yaw_rad)
    q_goal = arm.ik(target, pitch=pitch, yaw=yaw, q_seed=np.asarray(q_now_rad, float))
    trajectory = plan_joint_move(q_now_rad, q_goal, arm, moving_time_s, accel_time_s, rate_hz)
    check_trajectory(arm, trajectory, clearance_m=clearance_m)
    return trajectory


def trajectory_steps(steps: list[Step]) -> list[JointTrajectory]:
    """The trajectories of a plan, in order (for checks and previews)."""
    return [step.trajectory for step in steps if isinstance(step, TrajectoryStep)]
