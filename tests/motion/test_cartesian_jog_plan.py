"""The Cartesian hold-to-run jog's planner (armlab.motion.cartesian_jog), pure: the gripper point on its world line
with the pitch and yaw kept at every sample, the hold-to-run profile (ramp, hold, brake at the jog's acceleration),
and a boundary ahead (a check of the caller's) braked for before it, with the reason; never a sample past it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.cartesian_jog import BOUNDARY_MARGIN_M, jog_line, plan_cartesian_jog
from armlab.motion.errors import StepRefused
from armlab.motion.gripper_step import angle_difference_rad, gripper_poses

ARM = load_arm("rx200")
Q_DOWN = ARM.ik([0.0, 0.25, 0.12], pitch=math.pi / 2, yaw=0.0)
ACCEL_M_S2, HOLD_S, RATE_HZ = 0.5, 0.2, 100.0


@pytest.mark.parametrize("axis, v_m_s", [("x", 0.1), ("y", -0.1), ("z", 0.05)])
def test_a_jog_follows_its_line_keeping_pitch_and_yaw_and_stops_within_the_bound(axis, v_m_s):
    line = jog_line(ARM, Q_DOWN, axis)
    plan = plan_cartesian_jog(ARM, line, Q_DOWN, 0.0, v_m_s, HOLD_S, ACCEL_M_S2, RATE_HZ)
    poses = gripper_poses(ARM, plan.trajectory.positions_rad)
    offsets = np.array([p.position_m for p in poses]) - line.origin_m
    along = offsets @ line.direction
    assert np.linalg.norm(offsets - along[:, None] * line.direction, axis=1).max() < 1e-4
    assert max(abs(angle_difference_rad(p.pitch_rad, poses[0].pitch_rad)) for p in poses) < math.radians(0.05)
    assert max(abs(angle_difference_rad(p.yaw_rad, poses[0].yaw_rad)) for p in poses) < math.radians(0.05)
    assert plan.stopped_by is None
    assert abs(along[-1]) <= abs(v_m_s) * HOLD_S + v_m_s**2 / (2 * ACCEL_M_S2) + 1e-9
    assert np.allclose(plan.trajectory.positions_rad[-1], plan.trajectory.positions_rad[-2])  # at rest at its end
    speeds = np.abs(np.diff(along)) * RATE_HZ
    assert speeds.max() <= abs(v_m_s) + 1e-9 and np.abs(np.diff(np.diff(along))).max() * RATE_HZ**2 <= ACCEL_M_S2 + 1e-6


def test_a_boundary_ahead_is_braked_for_before_it_and_named():
    line = jog_line(ARM, Q_DOWN, "z")
    free = plan_cartesian_jog(ARM, line, Q_DOWN, 0.0, -0.1, HOLD_S, ACCEL_M_S2, RATE_HZ)
    wall_m = 0.6 * float(free.distances_m.min())  # a check of the caller's: the unchecked jog would go well past it

    def first_unsafe(trajectory):
        z = np.array([p.position_m[2] for p in gripper_poses(ARM, trajectory.positions_rad)]) - line.origin_m[2]
        bad = np.flatnonzero(z < wall_m)
        return (int(bad[0]), "the wall") if bad.size else None

    plan = plan_cartesian_jog(ARM, line, Q_DOWN, 0.0, -0.1, HOLD_S, ACCEL_M_S2, RATE_HZ, first_unsafe)
    assert plan.stopped_by == "the wall"
    assert first_unsafe(plan.trajectory) is None
    assert wall_m < plan.distances_m.min() <= wall_m + BOUNDARY_MARGIN_M + 0.003  # close before it, not far
    assert plan.distances_m[-1] == plan.distances_m.min()  # braked to rest there, no bounce


def test_a_jog_already_at_its_boundary_does_not_move_and_one_that_cannot_even_stand_is_refused():
    line = jog_line(ARM, Q_DOWN, "x")

    def moving_is_blocked(trajectory):
        return (1, "blocked") if np.ptp(trajectory.positions_rad, axis=0).max() > 1e-9 else None

    plan = plan_cartesian_jog(ARM, line, Q_DOWN, 0.0, 0.1, HOLD_S, ACCEL_M_S2, RATE_HZ, moving_is_blocked)
    assert plan.travel_m == 0.0 and plan.stopped_by == "blocked"
    with pytest.raises(StepRefused, match="blocked"):
        plan_cartesian_jog(ARM, line, Q_DOWN, 0.0, 0.1, HOLD_S, ACCEL_M_S2, RATE_HZ, lambda trajectory: (1, "blocked"))
