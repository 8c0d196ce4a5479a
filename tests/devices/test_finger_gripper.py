"""The finger gripper's outline (armlab.devices.finger_gripper, what the side-grasp planner keeps clear of
things) is the gripper the simulation builds: read back from the arm's MJCF (the palm box, the finger links,
the gripper point site) rather than from the formulas it is computed by."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from armlab.devices.arm_body import load_finger_gripper_outline
from armlab.devices.finger_gripper import load_finger_gripper_config
from armlab.devices.sim.config import load_sim_config
from armlab.devices.sim.mjcf import GRIPPER_SITE, ArmGeometry
from armlab.errors import ConfigError


def _numbers(element: ET.Element, attribute: str) -> list[float]:
    return [float(x) for x in element.get(attribute).split()]


def test_outline_is_the_simulated_gripper():
    worldbody, _ = ArmGeometry.load("rx200").mjcf(load_sim_config())
    link = ET.fromstring(f"<worldbody>{worldbody}</worldbody>").find(".//body[@name='gripper_link']")
    palm = link.find("geom[@name='palm']")
    site = link.find(f"site[@name='{GRIPPER_SITE}']")
    finger = link.find("body[@name='left_finger']")
    finger_link = finger.find("geom[@name='left_finger_link']")
    (half_x, half_y, half_z), (palm_x, _, _) = _numbers(palm, "size"), _numbers(palm, "pos")
    gripper_point_x = _numbers(site, "pos")[0]
    link_half_x, _, link_half_z = _numbers(finger_link, "size")
    link_x = _numbers(finger_link, "pos")[0]

    outline = load_finger_gripper_outline("rx200")

    assert outline.palm_half_height_m == pytest.approx(half_z)
    assert outline.palm_front_behind_m == pytest.approx(gripper_point_x - (palm_x + half_x))
    assert outline.palm_back_behind_m == pytest.approx(gripper_point_x - (palm_x - half_x))
    assert outline.open_outer_m == pytest.approx(half_y)
    assert outline.finger_half_height_m == pytest.approx(link_half_z)
    assert outline.finger_tip_beyond_m == pytest.approx(link_x + link_half_x - gripper_point_x)


def test_gripper_config_is_the_simulations():
    assert load_finger_gripper_config() == load_sim_config().gripper


def test_an_arm_without_fingers_has_no_outline():
    with pytest.raises(ConfigError, match="finger gripper outline"):
        load_finger_gripper_outline("ur3")
