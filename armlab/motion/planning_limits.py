"""The acceleration every planner plans at: each joint's hardware limit times PLANNING_ACCEL_FRACTION (one place).

Why below the limit: the ideal simulated servos follow a plan to within a few 1e-4 of its acceleration, not exactly
(a triangle's apex, where the acceleration reverses at once, measured 1.0009x the limit on the joint for a plan at
1.00004x; bench/motion_continuity.py's replacements up to 1.0004x), and a real servo tracks worse. The safety check
(armlab.motion.safety) and the benches still hold the plans and the measured joints to the hardware limit. Pure.
"""

from __future__ import annotations

import numpy as np

PLANNING_ACCEL_FRACTION = 0.99  # plans use this fraction of each joint's acceleration limit


def planning_accel_rad_s2(arm, within: float = 1.0) -> np.ndarray:
    """The acceleration (rad/s², shape (dof,)) to plan `arm`'s motion at: its limit x PLANNING_ACCEL_FRACTION, or x
    `within` when that is smaller (a planner that wants more room, e.g. for sampling, asks for less, never for more).
    arm: anything with accel_limit_rad_s2 (an arm model)."""
    return np.asarray(arm.accel_limit_rad_s2, dtype=float) * min(PLANNING_ACCEL_FRACTION, float(within))
