"""Straight vertical Cartesian segments of the gripper point (approach and lift), by IK at each sample.

The gripper point moves along a vertical line at fixed x, y with a trapezoidal speed profile
(speed/acceleration limits in m/s, m/s²), keeping its pitch and yaw; each sample is solved by IK
seeded with the previous one. If a joint would exceed its velocity or acceleration limit (near a
singularity), the segment is slowed down and re-solved. Pure: no device calls.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.motion.errors import DiscontinuousPath
from armlab.motion.pose_path import holds_full_pose, plan_straight_pose_segment
from armlab.motion.retime import branch_jump, plan_retimed
from armlab.motion.trajectory import (
    DEFAULT_RATE_HZ,
    minimum_time,
    sample_times,
)


def gripper_position_m(arm, q_rad) -> np.ndarray:
    """World position (3,) of the gripper point at q."""
    return np.asarray(arm.fk(np.asarray(q_rad, float)), float)[:3, 3]


def gripper_pitch_rad(arm, q_rad) -> float:
    """The pitch `arm.ik` means for the pose at q (ArmModel.pitch_of: below the horizontal in the vertical plane
    through the base axis, π/2 = straight down; beyond ±π/2 when pointing back toward the base axis, which
    an asin of the approach axis folds onto a different, often unreachable, orientation)."""
    return float(arm.pitch_of(np.asarray(q_rad, float)))


def vertical_profile_duration(distance_m: float, speed_m_s: float, accel_m_s2: float) -> float:
    """Duration of a rest-to-rest trapezoid over distance_m with the given speed and acceleration."""
    if distance_m <= 0.0:
        return 0.0
    return minimum_time(speed_m_s / distance_m, accel_m_s2 / distance_m)[0]


def solve_path(arm, q_start, targets_m: np.ndarray, pitch, yaw, label: str) -> np.ndarray:
    """IK at each target (N, 3) with pitch (a number or (N,)) and yaw; the first row is q_start.

    Uses the model's vectorised ik_batch (seeded with q_start) when it solves every point, else solves
    sample by sample, each seeded with the previous one (which also raises Unreachable with the reason).
    DiscontinuousPath (naming `label`, the joint and the height) if IK would switch branch.
    """
    pitches = np.broadcast_to(np.asarray(pitch, float), (len(targets_m),))
    positions = None
    if hasattr(arm, "ik_batch"):
        solved, ok = arm.ik_batch(targets_m[1:], pitch=pitches[1:], yaw=yaw, q_seed=np.asarray(q_start, float))
        if np.all(ok):
            positions = np.vstack([np.asarray(q_start, float)[None, :], np.asarray(solved, float)])
    if positions is None:
        positions = np.empty((len(targets_m), len(q_start)))
        positions[0] = q_start
        for index in range(1, len(targets_m)):
            positions[index] = arm.ik(targets_m[index], pitch=float(pitches[index]), yaw=yaw, q_seed=positions[index - 1])
    jump = branch_jump(positions)
    if jump is not None:
        sample, joint, jump_rad = jump
        names = getattr(arm, "joint_names", None)
        name = names[joint] if names is not None else f"joint {joint}"
        raise DiscontinuousPath(
            f"{label}: {name} jumps {jump_rad:.3f} rad at "
            f"z = {targets_m[sample + 1, 2] * 1000:.1f} mm (IK changed branch)"
        )
    return positions


def plan_path(
    arm, q_start, targets_at, pitch_at, yaw_rad, duration_s: float, ramp_s: float, label: str, rate_hz: float = DEFAULT_RATE_HZ
) -> JointTrajectory:
    """A rest-to-rest trajectory through IK of a path: targets_at(s) (N, 3) and pitch_at(s) (N,) for path
    fractions s in [0, 1] following a trapezoid of duration_s with ramps of ramp_s; slowed down (and
    re-solved) while a joint would exceed its velocity or acceleration limit (near a singularity)."""
    return plan_retimed(arm, lambda s: solve_path(arm, q_start, targets_at(s), pitch_at(s), yaw_rad, label),
                        duration_s, ramp_s, label, rate_hz)


def plan_vertical_segment(
    arm,
    q_start_rad,
    z_goal_m: float,
    pitch_rad: float | None = None,
    yaw_rad: float | None = None,
    speed_m_s: float = 0.1,
    accel_m_s2: float = 0.4,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> JointTrajectory:
    """Joint trajectory moving the gripper point straight up/down from fk(q_start) to height z_goal_m.

    pitch_rad: approach pitch below horizontal to hold (None: the start pose's). yaw_rad: the world yaw
    passed to IK for the wrist (None: IK keeps the seed's wrist). The first sample is q_start exactly.
    Raises ValueError for bad input, armlab.kinematics.Unreachable if a point of the line cannot be
    reached, DiscontinuousPath if IK would jump between branches. An arm with six joints or more holds
    the start's whole tool orientation instead (ik_pose; pitch_rad and yaw_rad are then the start's).
    """
    q_start = np.asarray(q_start_rad, dtype=float)
    if q_start.shape != (int(arm.dof),) or not np.all(np.isfinite(q_start)):
        raise ValueError(f"q_start must be {int(arm.dof)} finite joint angles, got {q_start.tolist()}")
    for name, value in (("z_goal_m", z_goal_m), ("speed_m_s", speed_m_s), ("accel_m_s2", accel_m_s2)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value}")
    if speed_m_s <= 0 or accel_m_s2 <= 0:
        raise ValueError(f"speed_m_s and accel_m_s2 must be > 0, got {speed_m_s}, {accel_m_s2}")
    start_m = gripper_position_m(arm, q_start)
    if holds_full_pose(arm):
        return plan_straight_pose_segment(arm, q_start, [start_m[0], start_m[1], z_goal_m], speed_m_s, accel_m_s2,
                                          f"vertical segment to z = {z_goal_m * 1000:.1f} mm", rate_hz)
    pitch = gripper_pitch_rad(arm, q_start) if pitch_rad is None else float(pitch_rad)
    distance_m = abs(z_goal_m - start_m[2])
    duration_s = vertical_profile_duration(distance_m, speed_m_s, accel_m_s2)
    if duration_s == 0.0:
        times = sample_times(0.0, rate_hz)
        return JointTrajectory(times_s=times, positions_rad=np.repeat(q_start[None, :], times.size, axis=0))

    ramp_s = minimum_time(speed_m_s / distance_m, accel_m_s2 / distance_m)[1]

    def targets_at(s: np.ndarray) -> np.ndarray:
        targets = np.repeat(start_m[None, :], s.size, axis=0)
        targets[:, 2] = start_m[2] + s * (z_goal_m - start_m[2])
        return targets

    return plan_path(
        arm, q_start, targets_at, lambda s: np.full(s.size, pitch), yaw_rad, duration_s, ramp_s,
        f"vertical segment to z = {z_goal_m * 1000:.1f} mm", rate_hz,
    )
