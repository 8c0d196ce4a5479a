"""Straight Cartesian segments of the gripper point in any direction (the side place's slide in over a
tower top and back out), by IK at each sample at a fixed pitch; the vertical case is
armlab.motion.cartesian. Trapezoidal speed profile; slowed down where a joint would exceed its limits;
DiscontinuousPath if IK would jump between branches. Pure: no device calls.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.motion.cartesian import (
    DiscontinuousPath,
    branch_jump,
    gripper_position_m,
    plan_retimed,
    vertical_profile_duration,
)
from armlab.motion.trajectory import DEFAULT_RATE_HZ, minimum_time, sample_times


def plan_line_segment(arm, q_start_rad, goal_m, pitch_rad: float, yaw_rad: float | None = None, speed_m_s: float = 0.1,
                      accel_m_s2: float = 0.4, rate_hz: float = DEFAULT_RATE_HZ) -> JointTrajectory:
    """Joint trajectory moving the gripper point along the straight line fk(q_start) → goal_m (world, m)
    at approach pitch pitch_rad (yaw as in arm.ik; None keeps the seed's wrist). The first sample is
    q_start exactly. Unreachable if a point of the line cannot be reached at that pitch."""
    q_start = np.asarray(q_start_rad, dtype=float)
    goal = np.asarray(goal_m, dtype=float)
    if q_start.shape != (int(arm.dof),) or not np.all(np.isfinite(q_start)) or goal.shape != (3,) or not np.all(np.isfinite(goal)):
        raise ValueError(f"plan_line_segment: q_start must be {int(arm.dof)} finite angles and goal_m 3 finite coordinates")
    start = gripper_position_m(arm, q_start)
    distance_m = float(np.linalg.norm(goal - start))
    duration_s = vertical_profile_duration(distance_m, speed_m_s, accel_m_s2)
    if duration_s == 0.0:
        times = sample_times(0.0, rate_hz)
        return JointTrajectory(times_s=times, positions_rad=np.repeat(q_start[None, :], times.size, axis=0))
    ramp_s = minimum_time(speed_m_s / distance_m, accel_m_s2 / distance_m)[1]
    label = f"line to ({goal[0] * 1000:.0f}, {goal[1] * 1000:.0f}, {goal[2] * 1000:.0f}) mm"

    def solve_at(s: np.ndarray) -> np.ndarray:
        positions = np.empty((s.size, q_start.size))
        positions[0] = q_start
        for index in range(1, s.size):
            positions[index] = arm.ik(start + s[index] * (goal - start), pitch=pitch_rad, yaw=yaw_rad, q_seed=positions[index - 1])
        jump = branch_jump(positions)
        if jump is not None:
            _, joint, jump_rad = jump
            raise DiscontinuousPath(f"{label}: joint {joint} jumps {jump_rad:.3f} rad (IK changed branch)")
        return positions

    return plan_retimed(arm, solve_at, duration_s, ramp_s, label, rate_hz)

