"""Jog steps of the tool for arms that hold a full pose (six or more joints): the whole orientation kept.

A Cartesian step (x, y or z) moves the tool point along the world axis with the start's rotation
matrix held at every sample (ik_pose); a pitch step turns the tool about its point, about the
horizontal axis that tilts the approach axis down (+) in the arm's vertical plane, nothing else.
(Roll steps turn the last joint, as for every arm: armlab.motion.gripper_step.) Every plan is checked
by FK of its samples against the asked motion (POSITION_TOL_M, ORIENTATION_TOL_RAD) before it is
returned, else StepRefused names the numbers. Pure: no devices.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.kinematics.rotations import rotation_about, rotation_angle_rad
from armlab.motion.errors import DiscontinuousPath, StepRefused
from armlab.motion.pose_path import plan_pose_path
from armlab.motion.trajectory import minimum_time

LINEAR_AXES = ("x", "y", "z")


def pitch_axis(arm, T_world_tool: np.ndarray) -> np.ndarray:
    """The world axis a +pitch step turns about: horizontal, across the arm's vertical plane through the
    tool point (z × radial direction), so the approach axis tilts down."""
    radial = T_world_tool[:2, 3] - np.asarray(arm.T_world_base, float)[:2, 3]
    if np.hypot(*radial) < 1e-9:  # over the base axis: the approach axis' own heading
        radial = T_world_tool[:2, 0]
    if np.hypot(*radial) < 1e-9:
        radial = np.array([1.0, 0.0])
    radial = radial / np.hypot(*radial)
    return np.array([-radial[1], radial[0], 0.0])


def step_goal_poses(arm, T_start: np.ndarray, axis: str, amount: float):
    """poses_at(s) (N, 4, 4) of the asked step from T_start: the line or the rotation at fraction s."""
    if axis in LINEAR_AXES:
        direction = np.zeros(3)
        direction[LINEAR_AXES.index(axis)] = amount

        def poses_at(s: np.ndarray) -> np.ndarray:
            poses = np.repeat(T_start[None], s.size, axis=0)
            poses[:, :3, 3] += s[:, None] * direction[None, :]
            return poses
    else:
        k = pitch_axis(arm, T_start)

        def poses_at(s: np.ndarray) -> np.ndarray:
            poses = np.repeat(T_start[None], s.size, axis=0)
            for index, fraction in enumerate(s):
                poses[index, :3, :3] = rotation_about(k, float(fraction) * amount) @ T_start[:3, :3]
            return poses
    return poses_at


def plan_pose_step(arm, q_start: np.ndarray, axis: str, amount: float, speeds, label: str, rate_hz: float,
                   position_tol_m: float, orientation_tol_rad: float) -> JointTrajectory:
    """A checked x|y|z|pitch step from q_start holding the full orientation (see the module doc)."""
    T_start = np.asarray(arm.fk(q_start), float)
    if axis in LINEAR_AXES:
        goal_z = T_start[2, 3] + (amount if axis == "z" else 0.0)
        if goal_z < 0.0:
            raise StepRefused(f"{label}: the gripper point would go to z = {goal_z * 1000:.1f} mm, below the board", "below the table")
        duration_s, ramp_s = minimum_time(speeds.linear_m_s / abs(amount), speeds.linear_accel_m_s2 / abs(amount))
    elif axis == "pitch":
        duration_s, ramp_s = minimum_time(speeds.angular_rad_s / abs(amount), speeds.angular_accel_rad_s2 / abs(amount))
    else:
        raise InvalidInput(f"plan_pose_step: axis must be x, y, z or pitch, got {axis!r}")
    poses_at = step_goal_poses(arm, T_start, axis, amount)
    try:
        trajectory = plan_pose_path(arm, q_start, poses_at, duration_s, ramp_s, label, rate_hz)
    except DiscontinuousPath as error:
        raise StepRefused(f"the arm cannot follow the step continuously: {error}", "discontinuous") from error
    verify_pose_step(arm, trajectory.positions_rad, T_start, axis, amount, label, position_tol_m, orientation_tol_rad)
    return trajectory


def verify_pose_step(arm, positions_rad, T_start: np.ndarray, axis: str, amount: float, label: str,
                     position_tol_m: float, orientation_tol_rad: float) -> None:
    """StepRefused unless FK of every sample stays on the asked motion: a linear step on its line with the
    start's rotation, a pitch step at the start's point with a rotation about the pitch axis, and the
    last sample at the asked end pose (each within the tolerances)."""
    T = np.asarray(arm.fk(np.asarray(positions_rad, float)), float).reshape(-1, 4, 4)
    worst_off_m, worst_turn = 0.0, 0.0
    if axis in LINEAR_AXES:
        direction = np.zeros(3)
        direction[LINEAR_AXES.index(axis)] = 1.0
        for pose in T:
            offset = pose[:3, 3] - T_start[:3, 3]
            worst_off_m = max(worst_off_m, float(np.linalg.norm(offset - float(offset @ direction) * direction)))
            worst_turn = max(worst_turn, rotation_angle_rad(T_start[:3, :3], pose[:3, :3]))
        worst_off_m = max(worst_off_m, float(np.linalg.norm(T[-1, :3, 3] - (T_start[:3, 3] + amount * direction))))
    else:
        k = pitch_axis(arm, T_start)
        for pose in T:
            worst_off_m = max(worst_off_m, float(np.linalg.norm(pose[:3, 3] - T_start[:3, 3])))
            # the rotation from the start must be about k: remove the turn about k it makes, the rest is error
            relative = pose[:3, :3] @ T_start[:3, :3].T
            vee = np.array([relative[2, 1] - relative[1, 2], relative[0, 2] - relative[2, 0], relative[1, 0] - relative[0, 1]])
            turned = float(np.arctan2(float(vee @ k), np.trace(relative) - 1.0))
            worst_turn = max(worst_turn, rotation_angle_rad(rotation_about(k, turned) @ T_start[:3, :3], pose[:3, :3]))
        end_error = rotation_angle_rad(rotation_about(k, amount) @ T_start[:3, :3], T[-1, :3, :3])
        if end_error > orientation_tol_rad:
            raise StepRefused(f"{label}: the tool would end {np.degrees(end_error):.2f}° off the asked rotation", "orientation")
    if worst_off_m > position_tol_m:
        raise StepRefused(f"{label}: the gripper point would leave the asked motion by {worst_off_m * 1000:.1f} mm", "off the line")
    if worst_turn > orientation_tol_rad:
        raise StepRefused(f"{label}: the tool's orientation would change by {np.degrees(worst_turn):.2f}°", "orientation")
