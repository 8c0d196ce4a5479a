"""A jog braking for a joint limit follows the braking curve: its acceleration does not chatter between braking and
accelerating from one sample to the next (before: full braking wherever the step toward the target was over, then that
step again at the next sample; the simulated servos followed the chatter at 1.05x the acceleration limit in
bench/motion_continuity.py), and it still stops inside the limit within the acceleration limit. Pure planning."""

from __future__ import annotations

import numpy as np

from armlab.kinematics import load_arm
from armlab.motion.jog import LIMIT_MARGIN_RAD, plan_jog

ARM = load_arm("rx200")
LOWER, UPPER = np.asarray(ARM.lower_rad, float), np.asarray(ARM.upper_rad, float)
ACCEL = np.asarray(ARM.accel_limit_rad_s2, float) * 0.98
RATE_HZ = 100.0


def _sign_reversals(positions: np.ndarray) -> int:
    """Consecutive samples whose accelerations (second differences) are both large and of opposite sign."""
    accel = np.diff(positions, n=2) * RATE_HZ**2
    large = np.abs(accel) > 0.5 * ACCEL[1]
    return int(np.sum(large[1:] & large[:-1] & (np.sign(accel[1:]) != np.sign(accel[:-1]))))


def test_a_jog_into_a_limit_brakes_along_the_braking_curve_without_chatter():
    q0 = np.array([0.0, UPPER[1] - 0.4, 0.0, 0.0, 0.0])
    trajectory = plan_jog(q0, np.zeros(5), [0.0, 0.8, 0.0, 0.0, 0.0], 2.0, LOWER, UPPER, ACCEL, RATE_HZ)
    shoulder = trajectory.positions_rad[:, 1]
    assert _sign_reversals(shoulder) == 0
    assert shoulder.max() <= UPPER[1] - LIMIT_MARGIN_RAD + 1e-12
    assert np.max(np.abs(np.diff(shoulder, n=2))) * RATE_HZ**2 <= ACCEL[1] * (1 + 1e-9)
    assert np.ptp(shoulder[-5:]) == 0.0  # at rest at the end


def test_re_planned_jogs_into_a_limit_do_not_chatter_either():
    """Heartbeats every 50 ms: each re-plan starts from the running plan's state (its last segment's velocity)."""
    q, v = np.array([0.0, 0.0, LOWER[2] + 0.4, 0.0, 0.0]), np.zeros(5)
    samples = [q.copy()]
    for _ in range(20):
        trajectory = plan_jog(q, v, [0.0, 0.0, -0.8, 0.0, 0.0], 0.2, LOWER, UPPER, ACCEL, RATE_HZ)
        kept = trajectory.positions_rad[:6]
        samples.extend(kept[1:])
        q, v = kept[-1].copy(), (kept[-1] - kept[-2]) * RATE_HZ
    elbow = np.asarray(samples)[:, 2]
    assert _sign_reversals(elbow) == 0
    assert elbow.min() >= LOWER[2] + LIMIT_MARGIN_RAD - 1e-12
