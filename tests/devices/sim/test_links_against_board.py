"""The trajectory check and the simulation agree on the arm's links against the board (issue 18 item 6).

bench/motion_continuity.py (seed 2) repeated a program whose waypoint the check passed while the simulated upper
arm, forearm and wrist lay 14 mm into the board: the check kept only the joint origins above it. Both now take the
links' thickness from the arm config (link_radii_m)."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.arm_body import load_arm_body
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.motion.safety import UnsafeTrajectory, check_trajectory

ARM = load_arm("rx200")
LINK_GEOMS = tuple(part.name for part in load_arm_body("rx200").parts if part.shape == "capsule")  # the links
INTO_THE_BOARD_Q = [-0.4172, 1.8365, -1.8452, -0.58, 1.7884]  # the bench's waypoint


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(realtime=False, realism="ideal")) as workcell:
        yield workcell


def passes_the_check(q) -> bool:
    try:
        check_trajectory(ARM, JointTrajectory(np.array([0.0, 0.01]), np.vstack([q, q])), check_rates=False)
        return True
    except UnsafeTrajectory:
        return False


def test_the_benchs_waypoint_into_the_board_is_refused_naming_the_link(cell):
    assert cell.contact_depth_at_mm(INTO_THE_BOARD_Q, LINK_GEOMS) > 10.0  # the simulation: 14 mm into the board
    with pytest.raises(UnsafeTrajectory, match="link at the .* thick .* below the board"):
        check_trajectory(ARM, JointTrajectory(np.array([0.0, 0.01]), np.vstack([INTO_THE_BOARD_Q] * 2)), check_rates=False)


def test_no_pose_the_check_passes_puts_a_simulated_link_into_the_board(cell):
    rng = np.random.default_rng(3)
    lower, upper = np.asarray(ARM.lower_rad), np.asarray(ARM.upper_rad)
    passed = low_passed = 0
    worst = 0.0
    for _ in range(3000):
        q = rng.uniform(lower, upper)
        q[1] = rng.uniform(0.8, upper[1])  # leaning forward, where the links come down to the board
        if not passes_the_check(q):
            continue
        passed += 1
        depth = cell.contact_depth_at_mm(q, LINK_GEOMS)
        worst = max(worst, depth)
        low_passed += ARM.joint_frames(q)[2][2, 3] < 0.06  # the elbow low over the board: the cases that matter
    assert passed > 300 and low_passed > 30, (passed, low_passed)
    assert worst <= 0.5, f"a pose the check passed has a simulated link {worst:.1f} mm into the board"


def test_an_arm_let_down_onto_the_board_may_move_out_but_not_stay_or_go_further_in():
    """A limp arm lies on the board (the page's arm panel test: home from there was refused at 'z = -0.0 mm'): a
    motion out of it passes, standing there or going deeper does not."""
    from armlab.motion.trajectory import plan_joint_move

    into = np.asarray(INTO_THE_BOARD_Q)
    out = plan_joint_move(into, ARM.home_rad, ARM)
    check_trajectory(ARM, out, check_rates=False)
    deeper = into + np.array([0.0, 0.05, 0.0, 0.0, 0.0])
    with pytest.raises(UnsafeTrajectory, match="below the board"):
        check_trajectory(ARM, plan_joint_move(into, deeper, ARM), check_rates=False)
