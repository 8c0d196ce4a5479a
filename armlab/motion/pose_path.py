"""Cartesian paths that keep the tool's full orientation, for arms with six or more joints (ik_pose).

A 5-joint arm cannot hold an arbitrary orientation, so its Cartesian paths hold pitch and yaw
(armlab.motion.cartesian); an arm with ik_pose and at least six joints holds the whole rotation
matrix of the tool frame instead: each sample is a full world pose, solved by the model's numerical
ik_pose (batched, seeded with the start; sample by sample when the batch misses one), then retimed
like any Cartesian path. Pure: no devices.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.kinematics.errors import Unreachable
from armlab.motion.errors import DiscontinuousPath
from armlab.motion.retime import MAX_SAMPLE_STEP_RAD, branch_jump, plan_retimed
from armlab.motion.trajectory import DEFAULT_RATE_HZ, minimum_time, sample_times

FULL_POSE_MIN_DOF = 6  # arms with at least this many joints hold the whole tool orientation


def holds_full_pose(arm) -> bool:
    """True when the arm model can hold a full tool pose along a path (>= 6 joints and ik_pose)."""
    return int(getattr(arm, "dof", 0)) >= FULL_POSE_MIN_DOF and hasattr(arm, "ik_pose")


def top_down_rotation(yaw_rad: float) -> np.ndarray:
    """World rotation of a tool pointing straight down (tool x = world -z) with its y axis at yaw_rad
    from world +x in the board plane; tool z = x × y."""
    x_axis = np.array([0.0, 0.0, -1.0])
    y_axis = np.array([math.cos(yaw_rad), math.sin(yaw_rad), 0.0])
    return np.stack([x_axis, y_axis, np.cross(x_axis, y_axis)], axis=1)


def solve_pose_path(arm, q_start, poses: np.ndarray, label: str) -> np.ndarray:
    """ik_pose of each world pose (N, 4, 4), the first row replaced by q_start; DiscontinuousPath if
    the joints would jump (IK changed branch), Unreachable (from the model) if a pose has no solution."""
    q_start = np.asarray(q_start, float)
    solved, ok = arm.ik_pose_batch(poses[1:], q_seed=q_start)
    positions = np.vstack([q_start[None, :], np.asarray(solved, float)])
    if not np.all(ok):  # seed each miss with the previous sample (raises Unreachable with the residual)
        for index in range(1, len(poses)):
            if not ok[index - 1] or np.abs(positions[index] - positions[index - 1]).max() > MAX_SAMPLE_STEP_RAD:
                positions[index] = arm.ik_pose(poses[index], q_seed=positions[index - 1])
    jump = branch_jump(positions)
    if jump is not None:
        sample, joint, jump_rad = jump
        raise DiscontinuousPath(
            f"{label}: {arm.joint_names[joint]} jumps {jump_rad:.3f} rad at "
            f"({', '.join(f'{v * 1000:.1f}' for v in poses[sample + 1, :3, 3])}) mm (IK changed branch)"
        )
    return positions


def plan_pose_path(arm, q_start, poses_at, duration_s: float, ramp_s: float, label: str,
                   rate_hz: float = DEFAULT_RATE_HZ) -> JointTrajectory:
    """A rest-to-rest trajectory through ik_pose of poses_at(s) (N, 4, 4) for path fractions s in [0, 1]
    on a trapezoid of duration_s (ramps ramp_s), slowed down while a joint would pass its velocity or
    acceleration limit (as armlab.motion.cartesian.plan_path)."""
    return plan_retimed(arm, lambda s: solve_pose_path(arm, q_start, poses_at(s), label), duration_s, ramp_s, label, rate_hz)


def plan_straight_pose_segment(arm, q_start_rad, goal_m, speed_m_s: float, accel_m_s2: float, label: str | None = None,
                               rate_hz: float = DEFAULT_RATE_HZ) -> JointTrajectory:
    """The tool point on a straight line from fk(q_start) to goal_m (world, metres) with the start's
    rotation held at every sample (full pose). The first sample is q_start exactly."""
    q_start = np.asarray(q_start_rad, float)
    T_start = np.asarray(arm.fk(q_start), float)
    goal = np.asarray(goal_m, float)
    if goal.shape != (3,) or not np.all(np.isfinite(goal)):
        raise InvalidInput(f"goal_m must be 3 finite coordinates in metres, got {np.asarray(goal_m).tolist()}")
    if not (speed_m_s > 0.0 and accel_m_s2 > 0.0):
        raise InvalidInput(f"speed_m_s and accel_m_s2 must be > 0, got {speed_m_s}, {accel_m_s2}")
    offset = goal - T_start[:3, 3]
    distance_m = float(np.linalg.norm(offset))
    label = label or f"straight segment to ({', '.join(f'{v * 1000:.1f}' for v in goal)}) mm"
    if distance_m < 1e-9:
        times = sample_times(0.0, rate_hz)
        return JointTrajectory(times_s=times, positions_rad=np.repeat(q_start[None, :], times.size, axis=0))
    duration_s, ramp_s = minimum_time(speed_m_s / distance_m, accel_m_s2 / distance_m)

    def poses_at(s: np.ndarray) -> np.ndarray:
        poses = np.repeat(T_start[None], s.size, axis=0)
        poses[:, :3, 3] = T_start[:3, 3][None, :] + s[:, None] * offset[None, :]
        return poses

    return plan_pose_path(arm, q_start, poses_at, duration_s, ramp_s, label, rate_hz)


def pose_rotation(arm, position_m, pitch_rad: float, heading_rad: float) -> np.ndarray:
    """World rotation of a tool at position_m whose approach axis (x) is pitch_rad below the horizontal in
    the vertical plane through the arm's base axis, pointing away from it, and whose y axis lies as close
    to the board-plane heading heading_rad as that allows (exactly on it when pointing straight down)."""
    radial = np.asarray(position_m, float)[:2] - np.asarray(arm.T_world_base, float)[:2, 3]
    radial = radial / np.linalg.norm(radial) if np.linalg.norm(radial) > 1e-9 else np.array([1.0, 0.0])
    approach = np.array([math.cos(pitch_rad) * radial[0], math.cos(pitch_rad) * radial[1], -math.sin(pitch_rad)])
    heading = np.array([math.cos(heading_rad), math.sin(heading_rad), 0.0])
    y_axis = heading - float(heading @ approach) * approach
    if np.linalg.norm(y_axis) < 1e-6:  # the heading lies along the approach: any perpendicular
        y_axis = np.cross([0.0, 0.0, 1.0], approach)
    y_axis /= np.linalg.norm(y_axis)
    return np.stack([approach, y_axis, np.cross(approach, y_axis)], axis=1)


def tool_heading_rad(T_world_tool: np.ndarray) -> float:
    """Heading in the board plane of the tool's y axis (the closing axis of fingers; the cup's own y axis),
    or of its z axis when y stands (nearly) vertical."""
    axis = T_world_tool[:3, 1] if np.hypot(*T_world_tool[:2, 1]) > 0.2 else T_world_tool[:3, 2]
    return math.atan2(float(axis[1]), float(axis[0]))


def solve_pose_move(arm, position_m, pitch_rad: float | None, yaw_rad: float | None, q_seed) -> np.ndarray:
    """Joints of a pose move on an arm that holds a full pose (ik_pose): the tool at position_m with its
    approach pitch_rad below the horizontal (None: straight down, else the steepest the arm reaches, as
    ArmModel.ik searches) and its y axis at heading yaw_rad (None: the heading it has now, kept; a
    yaw takes the quarter turn nearest the seed, the faces of a block being a quarter turn apart).
    Raises Unreachable (from the model) when no such pose is reachable."""
    q_seed = np.asarray(q_seed, float)
    target = np.asarray(position_m, float)
    headings = [tool_heading_rad(np.asarray(arm.fk(q_seed), float))] if yaw_rad is None else \
        [float(yaw_rad) + k * math.pi / 2 for k in range(4)]
    best, best_cost, error = None, math.inf, None
    for heading in headings:
        T = np.eye(4)
        T[:3, :3] = pose_rotation(arm, target, math.pi / 2 if pitch_rad is None else float(pitch_rad), heading)
        T[:3, 3] = target
        try:
            q = arm.ik_pose(T, q_seed=q_seed)
        except Unreachable as failure:
            error = error or failure
            continue
        cost = float(np.abs(q - q_seed).sum())
        if cost < best_cost:
            best, best_cost = q, cost
    if best is not None:
        return best
    if pitch_rad is None:  # not straight down: the steepest pitch that reaches (the model's search)
        return np.asarray(arm.ik(target, pitch=None, yaw=yaw_rad, q_seed=q_seed), float)
    raise error
