"""The status' device part on its own (armlab.station.status.ArmReadings), with fake devices and the RX200's model:
the joints read (the last good ones while the arm cannot be read), moving by the arm's word or by a joint's speed,
the gripper's state (defaults while it cannot be read) and the gripper's pose from the forward kinematics."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from armlab.devices.arm import JointState
from armlab.kinematics import load_arm
from armlab.station.status import ArmReadings

MOVING_SPEED_RAD_S = 0.05
ARM = load_arm("rx200")


class FakeArm:
    def __init__(self) -> None:
        self.q, self.velocity, self.moving, self.lost = np.zeros(5), np.zeros(5), False, False

    def read_joint_state(self) -> JointState:
        if self.lost:
            raise ConnectionError("unplugged")
        return JointState(self.q.copy(), self.velocity.copy(), 0.0)

    def is_moving(self) -> bool:
        return self.moving


class FakeGripper:
    def __init__(self) -> None:
        self.lost = False

    def read_state(self):
        if self.lost:
            raise TimeoutError("no answer")
        return SimpleNamespace(width_m=0.03, holding=True, command="grasp")


def test_the_readings_of_an_arm_at_rest():
    arm, gripper = FakeArm(), FakeGripper()
    arm.q = np.array([0.1, -0.2, 0.3, 0.4, -0.5])
    readings = ArmReadings(arm, gripper, ARM, MOVING_SPEED_RAD_S).read()
    assert readings["joints_rad"] == [0.1, -0.2, 0.3, 0.4, -0.5] and readings["moving"] is False
    assert readings["gripper"] == {"width_m": 0.03, "holding": True, "command": "grasp"}
    assert readings["joint_names"] == list(ARM.joint_names) and len(readings["joint_limits_rad"]) == 5
    expected = ARM.fk(arm.q)[:3, 3]
    assert np.allclose(readings["gripper_pose"]["position_m"], expected)


def test_moving_by_the_arms_word_or_by_a_joints_speed():
    arm = FakeArm()
    readings = ArmReadings(arm, FakeGripper(), ARM, MOVING_SPEED_RAD_S)
    arm.velocity = np.array([0.0, 0.0, -0.06, 0.0, 0.0])  # faster than MOVING_SPEED_RAD_S, either sign
    assert readings.read()["moving"] is True
    arm.velocity = np.array([0.0, 0.0, 0.04, 0.0, 0.0])
    assert readings.read()["moving"] is False
    arm.moving = True
    assert readings.read()["moving"] is True


def test_a_lost_arm_shows_its_last_reading_and_a_lost_gripper_the_defaults():
    arm, gripper = FakeArm(), FakeGripper()
    readings = ArmReadings(arm, gripper, ARM, MOVING_SPEED_RAD_S)
    arm.q = np.full(5, 0.2)
    readings.read()
    arm.q, arm.lost, gripper.lost = np.full(5, 0.9), True, True
    lost = readings.read()
    assert lost["joints_rad"] == [0.2] * 5 and lost["moving"] is False
    assert lost["gripper"] == {"width_m": 0.0, "holding": False, "command": "release"}


def test_an_arm_lost_from_the_start_shows_home():
    arm = FakeArm()
    arm.lost = True
    assert np.allclose(ArmReadings(arm, FakeGripper(), ARM, MOVING_SPEED_RAD_S).read()["joints_rad"], ARM.home_rad)


def test_no_arm_no_joints():
    arm = FakeArm()
    arm.q = np.zeros(0)
    readings = ArmReadings(arm, FakeGripper(), None, MOVING_SPEED_RAD_S).read()
    assert readings["joints_rad"] == [] and readings["joint_names"] == [] and readings["gripper_pose"] is None
