"""Straight Cartesian segments at a fixed pitch (armlab.motion.line, the side place's slide over a tower
top): the gripper point stays on the line and the pitch holds at every sample, the joints respect their
velocity limits, and a line out of reach is refused before anything moves."""

import math

import numpy as np
import pytest

from armlab.kinematics import Unreachable, load_arm
from armlab.motion.line import plan_line_segment

ARM = load_arm("rx200")


def test_the_gripper_point_follows_the_line_at_the_pitch():
    pitch = math.radians(5.0)
    start = np.array([0.08, 0.09, 0.48])
    goal = np.array([0.13, 0.16, 0.47])
    q_start = ARM.ik(start, pitch=pitch, yaw=None, q_seed=np.zeros(5))
    trajectory = plan_line_segment(ARM, q_start, goal, pitch)
    points = np.array([ARM.fk(q)[:3, 3] for q in trajectory.positions_rad])
    direction = (goal - start) / np.linalg.norm(goal - start)
    off_line = np.linalg.norm(np.cross(points - start, direction), axis=1)
    assert off_line.max() < 1e-4
    assert np.allclose(points[0], start, atol=1e-6) and np.allclose(points[-1], goal, atol=1e-4)
    assert max(abs(ARM.pitch_of(q) - pitch) for q in trajectory.positions_rad) < 1e-4
    velocity = np.abs(np.diff(trajectory.positions_rad, axis=0)) / np.diff(trajectory.times_s)[:, None]
    assert np.all(velocity <= np.asarray(ARM.velocity_limit_rad_s) + 1e-6)


def test_a_line_out_of_reach_is_refused():
    q_start = ARM.ik([0.0, 0.25, 0.40], pitch=0.0, yaw=None, q_seed=np.zeros(5))
    with pytest.raises(Unreachable):
        plan_line_segment(ARM, q_start, [0.0, 0.25, 0.60], 0.0)
