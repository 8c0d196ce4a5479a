"""Joint paths solved by IK sample by sample: the branch-jump check and the retiming that slows a path
until every joint keeps its limits. Shared by the pitch/yaw paths (armlab.motion.cartesian) and the
full-pose paths (armlab.motion.pose_path). Pure: no device calls.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PlanRefused
from armlab.motion.planning_limits import planning_accel_rad_s2
from armlab.motion.trajectory import DEFAULT_RATE_HZ, LIMIT_MARGIN, retime_path, sample_times, trapezoid_profile

# Largest joint change between two 100 Hz samples that is still one continuous IK branch (radians).
MAX_SAMPLE_STEP_RAD = 0.25
_MAX_RETIMES = 6


def branch_jump(positions: np.ndarray) -> tuple[int, int, float] | None:
    """(sample, joint, jump_rad) of the largest joint change between consecutive samples when it is more
    than MAX_SAMPLE_STEP_RAD (IK changed branch: sample is the index of the step's first row), else None."""
    jumps = np.abs(np.diff(positions, axis=0))
    if not jumps.size:
        return None
    sample, joint = np.unravel_index(int(np.argmax(jumps)), jumps.shape)
    jump = jumps[sample, joint]
    return (int(sample), int(joint), float(jump)) if jump > MAX_SAMPLE_STEP_RAD else None


def plan_retimed(arm, solve_at, duration_s: float, ramp_s: float, label: str, rate_hz: float = DEFAULT_RATE_HZ) -> JointTrajectory:
    """A rest-to-rest trajectory through solve_at(s) (joint rows for path fractions s in [0, 1]) on a
    trapezoid of duration_s with ramps of ramp_s; stretched (and re-solved) while a joint would exceed
    its velocity or acceleration limit (near a singularity). PlanRefused naming `label` when
    _MAX_RETIMES stretches are not enough."""
    velocity_limit = np.asarray(arm.velocity_limit_rad_s, float) * LIMIT_MARGIN
    accel_limit = planning_accel_rad_s2(arm)
    for _ in range(_MAX_RETIMES):
        times = sample_times(duration_s, rate_hz)
        s = trapezoid_profile(times, duration_s, ramp_s)
        positions = solve_at(s)
        slow_down = retime_path(positions, times, velocity_limit, accel_limit)
        if slow_down <= 1.0:
            return JointTrajectory(times_s=times, positions_rad=positions)
        # Slowing by k scales velocity by 1/k and acceleration by 1/k²: stretch both phases.
        factor = slow_down * 1.02
        duration_s *= factor
        ramp_s *= factor
    raise PlanRefused(f"{label}: joints still too fast after {_MAX_RETIMES} slow-downs (too close to a singularity)")
