"""The side grasp's gripper outline is the arm's own (config/arms/<arm>.yaml), not the RX200's for every arm."""

import math

import numpy as np
import pytest

from armlab.devices.finger_gripper import load_finger_gripper_outline
from armlab.errors import ConfigError
from armlab.kinematics import load_arm
from armlab.skills.side_grasp import gripper_points, lowest_below_gripper_point_m


def test_the_outline_comes_from_the_model_it_is_asked_for():
    rx200 = load_arm("rx200")
    outline = load_finger_gripper_outline("rx200")
    q = np.zeros(rx200.dof)
    points = gripper_points(rx200, q)
    T = np.asarray(rx200.fk(q))
    local = (points[0] - T[:3, 3]) @ T[:3, :3]  # in the gripper's frame
    assert points.shape == (1, 6, 3)
    assert np.max(np.abs(local[:, 1])) == pytest.approx(outline.open_outer_m)  # the open fingers' outer faces
    # Top-down (pitch 90 deg) the lowest part is the finger tip below the gripper point.
    assert lowest_below_gripper_point_m("rx200", math.pi / 2) == pytest.approx(max(outline.finger_tip_beyond_m, -outline.palm_front_behind_m))


def test_an_arm_without_fingers_has_no_side_grasp_outline():
    ur3 = load_arm("ur3")
    with pytest.raises(ConfigError):
        gripper_points(ur3, np.zeros(ur3.dof))
