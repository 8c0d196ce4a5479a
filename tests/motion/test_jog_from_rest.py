"""A jog from rest starts at rest: its first sample holds, so the arm, at rest before the trajectory, reaches the first
motion sample within the acceleration limit. Before, the first sample already moved at accel*dt (the velocity steps
once per sample and each step moved at the new velocity): from rest that needs twice the limit over the first sample,
which the samples' own second differences do not show (the trajectory starts there). The ideal simulated servos,
following their command exactly, measured 1.20x the limit over 20 ms (bench/motion_continuity.py seed 4). Pure
planning."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.jog import plan_jog

ARM = load_arm("rx200")
LOWER, UPPER = np.asarray(ARM.lower_rad, float), np.asarray(ARM.upper_rad, float)
ACCEL = np.asarray(ARM.accel_limit_rad_s2, float) * 0.98
RATE_HZ = 100.0
DT_S = 1.0 / RATE_HZ


@pytest.mark.parametrize("velocity", [[0.8, 0.0, 0.0, 0.0, 0.0], [0.3, -0.5, 0.2, 0.8, -0.8]])
def test_a_jog_from_rest_reaches_its_first_sample_within_the_acceleration_limit(velocity):
    trajectory = plan_jog(np.zeros(5), np.zeros(5), velocity, 0.5, LOWER, UPPER, ACCEL, RATE_HZ)
    positions = trajectory.positions_rad
    # at rest where it starts: the first sample is reached at a constant acceleration of 2 * step / dt^2 at least
    first = 2.0 * np.abs(positions[1] - positions[0]) / DT_S**2
    assert np.all(first <= ACCEL * (1 + 1e-9)), f"{first / ACCEL} x the limit to its first sample"
    later = np.abs(np.diff(positions, n=2, axis=0)) / DT_S**2
    assert np.all(later <= ACCEL * (1 + 1e-9))
    assert np.allclose(positions[-1] - positions[-2], 0.0)  # and it ends at rest


def test_a_jog_that_takes_over_a_moving_one_does_not_hold_first():
    v0 = np.array([0.5, 0.0, 0.0, 0.0, 0.0])
    trajectory = plan_jog(np.zeros(5), v0, v0, 0.5, LOWER, UPPER, ACCEL, RATE_HZ)
    assert trajectory.positions_rad[1, 0] == pytest.approx(v0[0] * DT_S)
