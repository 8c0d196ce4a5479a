"""Straight Cartesian segments of the gripper point in any direction (the side place's slide in over a
tower top and back out), by IK at each sample at a fixed pitch; the vertical case is
armlab.motion.cartesian. Trapezoidal speed profile; slowed down where a joint would exceed its limits;
DiscontinuousPath if IK would jump between branches. Pure: no device calls.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.motion.cartesian import MAX_SAMPLE_STEP_RAD, DiscontinuousPath, gripper_position_m, vertical_profile_duration
from armlab.motion.trajectory import DEFAULT_RATE_HZ, LIMIT_MARGIN, minimum_time, retime_path, sample_times, trapezoid_profile

_MAX_RETIMES = 6


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
    velocity_limit = np.asarray(arm.velocity_limit_rad_s, float) * LIMIT_MARGIN
    accel_limit = np.asarray(arm.accel_limit_rad_s2, float) * LIMIT_MARGIN
    for _ in range(_MAX_RETIMES):
        times = sample_times(duration_s, rate_hz)
        s = trapezoid_profile(times, duration_s, ramp_s)
        positions = np.empty((s.size, q_start.size))
        positions[0] = q_start
        for index in range(1, s.size):
            positions[index] = arm.ik(start + s[index] * (goal - start), pitch=pitch_rad, yaw=yaw_rad, q_seed=positions[index - 1])
        jumps = np.abs(np.diff(positions, axis=0))
        if jumps.size and jumps.max() > MAX_SAMPLE_STEP_RAD:
            sample, joint = np.unravel_index(int(np.argmax(jumps)), jumps.shape)
            raise DiscontinuousPath(f"line to ({goal[0] * 1000:.0f}, {goal[1] * 1000:.0f}, {goal[2] * 1000:.0f}) mm: joint {joint} "
                                    f"jumps {jumps[sample, joint]:.3f} rad (IK changed branch)")
        slow_down = retime_path(positions, times, velocity_limit, accel_limit)
        if slow_down <= 1.0:
            return JointTrajectory(times_s=times, positions_rad=positions)
        factor = slow_down * 1.02
        duration_s *= factor
        ramp_s *= factor
    raise ValueError(f"line to ({goal[0] * 1000:.0f}, {goal[1] * 1000:.0f}, {goal[2] * 1000:.0f}) mm: joints still too fast "
                     f"after {_MAX_RETIMES} slow-downs (too close to a singularity)")

