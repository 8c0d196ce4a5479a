"""check_trajectory on the 6-joint UR3 of the ur3_suction workcell (its base pose on the board): every joint's
position limit is checked, the sixth included, and the board is checked at every link point and the cup's
tool point; only the base-fixed first joint origin (z = 0, the UR3 stands on the board) is exempt.

Truth: the arm file's limits (config/arms/ur3.yaml, read here) and forward kinematics of the DH table
(which link point is under the board). Pure: no simulation, < 1 s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from armlab.devices.arm import JointTrajectory
from armlab.motion.safety import UnsafeTrajectory, check_trajectory
from armlab.motion.trajectory import plan_joint_move
from armlab.workcell import load_workcell_arm

UR3 = load_workcell_arm("ur3_suction")
ARM_FILE = yaml.safe_load((Path(__file__).resolve().parents[2] / "config" / "arms" / "ur3.yaml").read_text())
CUP_DOWN = np.array([0.3, -1.2, 1.3, -1.7, -1.57, 0.2])  # the cup pointing down, 0.23 m above the board
ELBOW_DOWN = np.array([0.0, 0.8, -2.4, -1.57, 0.0, 0.0])  # upper arm pitched below horizontal, forearm up


def heights_m(q) -> np.ndarray:
    """z of the base, every joint origin and the tool point (DH forward kinematics)."""
    return np.asarray(UR3.joint_frames(np.asarray(q, dtype=float)))[:, 2, 3]


def yaml_limits_rad() -> list[tuple[str, float, float]]:
    limits = ARM_FILE["limits"]
    return [(name, np.radians(lower), np.radians(upper))
            for name, lower, upper in zip(ARM_FILE["joint_names"], limits["lower_deg"], limits["upper_deg"], strict=True)]


@pytest.mark.parametrize("joint", range(6))
@pytest.mark.parametrize("side", ["lower", "upper"])
def test_every_ur3_joint_beyond_its_limit_is_refused_naming_it(joint, side):
    name, lower, upper = yaml_limits_rad()[joint]
    positions = np.tile(CUP_DOWN, (5, 1))
    positions[3, joint] = lower - 0.01 if side == "lower" else upper + 0.01
    with pytest.raises(UnsafeTrajectory, match=rf"^{name} = -?\d+\.\d{{4}} rad at t = 0\.030 s is outside its limits"):
        check_trajectory(UR3, JointTrajectory(np.arange(5) * 0.01, positions), check_rates=False)
    positions[3, joint] = lower + 0.01 if side == "lower" else upper - 0.01  # just inside: the limit alone is fine
    if heights_m(positions[3])[1:].min() > 0.0:  # (shoulder_lift at +-2 pi turns the cup under the board)
        check_trajectory(UR3, JointTrajectory(np.arange(5) * 0.01, positions), check_rates=False)


def test_a_ur3_move_driving_the_cup_into_the_table_is_refused():
    # Lower the shoulder until the cup's lip is 20 mm into the board, everything else above it.
    goal = CUP_DOWN.copy()
    while heights_m(goal)[-1] > -0.020:
        goal[1] += 0.01
    assert (heights_m(goal)[1:-1] > 0.05).all() and heights_m(CUP_DOWN).min() >= 0.0
    check_trajectory(UR3, plan_joint_move(CUP_DOWN, CUP_DOWN + [0.2, 0.0, 0.0, 0.0, 0.0, 0.3], UR3))  # above: fine
    with pytest.raises(UnsafeTrajectory, match=r"gripper point at z = -?\d+\.\d mm at t = \d+\.\d{3} s is below the board"):
        check_trajectory(UR3, plan_joint_move(CUP_DOWN, goal, UR3))


def test_a_ur3_link_into_the_table_is_refused_with_the_cup_above_it():
    z = heights_m(ELBOW_DOWN)
    assert z[2] < -0.01 and z[-1] > 0.1 and (np.delete(z, [0, 2]) > 0.1).all()  # only the elbow origin is under
    with pytest.raises(UnsafeTrajectory, match=r"elbow origin at z = -\d+\.\d mm .* is below the board"):
        check_trajectory(UR3, JointTrajectory(np.array([0.0, 0.01]), np.tile(ELBOW_DOWN, (2, 1))), check_rates=False)


def test_clearance_applies_to_the_ur3_cup_point():
    low = CUP_DOWN + [0.0, 0.3, 0.0, 0.0, 0.0, 0.0]  # the cup 0.11 m above the board, every joint origin higher
    z = heights_m(low)
    assert 0.10 < z[-1] < 0.12 and (z[1:-1] > 0.15).all()
    positions = np.tile(low, (2, 1))
    check_trajectory(UR3, JointTrajectory(np.array([0.0, 0.01]), positions), clearance_m=0.1, check_rates=False)
    with pytest.raises(UnsafeTrajectory, match=r"gripper point .* below the board surface \+ clearance \(130\.0 mm\)"):
        check_trajectory(UR3, JointTrajectory(np.array([0.0, 0.01]), positions), clearance_m=0.13, check_rates=False)
