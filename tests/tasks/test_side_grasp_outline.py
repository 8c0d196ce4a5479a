"""The side grasp's gripper outline is the arm's own (config/arms/<arm>.yaml), not the RX200's for every arm."""

import math

import numpy as np
import pytest

from armlab.devices.arm_body import load_arm_body, load_finger_gripper_outline
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


def test_the_outline_is_the_arm_bodys_palm_and_fingers_where_the_model_puts_them():
    """At random joints the side grasp's gripper points are the corners of the arm body's palm (its mid-plane)
    and the finger links' far ends: the outline is read off the one body, not kept beside it."""
    rx200, body = load_arm("rx200"), load_arm_body("rx200")
    rng = np.random.default_rng(4)
    q = rng.uniform(rx200.lower_rad, rx200.upper_rad, size=(6, rx200.dof))
    points = gripper_points(rx200, q)  # (N, 6, 3): tips, palm front, palm back; each on both sides
    placed = body.place(rx200, q)
    names = [part.name for part in placed.parts]
    palm, finger = placed.poses[:, names.index("palm")], placed.poses[:, names.index("left_finger_link")]
    palm_half = placed.parts[names.index("palm")].size_m
    finger_half = placed.parts[names.index("left_finger_link")].size_m
    for n in range(len(q)):
        corners = [palm[n, :3, 3] + sx * palm_half[0] * palm[n, :3, 0] + sy * palm_half[1] * palm[n, :3, 1]
                   for sx in (1.0, -1.0) for sy in (-1.0, 1.0)]
        np.testing.assert_allclose(points[n, 2:], corners, atol=1e-9)
        T = np.asarray(rx200.fk(q[n]))
        finger_end = finger[n, :3, 3] + finger_half[0] * finger[n, :3, 0]
        assert (points[n, 0] - T[:3, 3]) @ T[:3, 0] == pytest.approx((finger_end - T[:3, 3]) @ T[:3, 0])
