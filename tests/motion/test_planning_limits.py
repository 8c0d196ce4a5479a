"""Every planner plans at PLANNING_ACCEL_FRACTION of each joint's acceleration limit (armlab.motion.planning_limits),
and the safety check still allows the whole hardware limit."""

from __future__ import annotations

import numpy as np

from armlab.kinematics import load_arm
from armlab.motion.blend import arm_limits
from armlab.motion.planning_limits import PLANNING_ACCEL_FRACTION
from armlab.motion.time_warp import path_derivatives
from armlab.motion.trajectory import plan_joint_move_timed

ARM = load_arm("rx200")
LIMIT = np.asarray(ARM.accel_limit_rad_s2, dtype=float)


def test_the_fraction_leaves_room_below_the_limit():
    assert 0.95 <= PLANNING_ACCEL_FRACTION < 1.0


def test_the_fastest_trapezoid_accelerates_at_the_planning_fraction():
    """Before: planned at (1 - 1e-6)x the limit."""
    _, timing = plan_joint_move_timed(np.zeros(5), np.array([2.0, 0.0, 0.0, 0.0, 0.0]), ARM)
    ratio = float(timing.peak_accel_rad_s2[0] / LIMIT[0])
    assert PLANNING_ACCEL_FRACTION - 0.03 < ratio <= PLANNING_ACCEL_FRACTION + 1e-9  # (a bit less: on the sample grid)


def test_the_sampled_trapezoid_stays_at_the_planning_fraction():
    """Its samples' second differences, as the servos are given them."""
    trajectory, _ = plan_joint_move_timed(np.zeros(5), np.array([0.0, 0.0, 0.0, 1.2, -1.0]), ARM)
    _, _, accel = path_derivatives(trajectory)
    assert np.all(np.abs(accel) <= LIMIT * PLANNING_ACCEL_FRACTION * (1 + 1e-6))


def test_jerk_limited_plans_take_at_most_the_planning_fraction():
    assert np.all(arm_limits(ARM, margin=1.0).accel_rad_s2 <= LIMIT * PLANNING_ACCEL_FRACTION + 1e-12)
    assert np.allclose(arm_limits(ARM, margin=0.5).accel_rad_s2, LIMIT * 0.5)  # a smaller margin is kept
