"""The station's arm model with a calibration (armlab.kinematics.calibrated_arm): its IK meets its own FK (position
and pitch), batched and pose IK too; without a calibration it is the nominal model."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.kinematics.arm_calibration import ArmCalibration
from armlab.kinematics.calibrated_arm import CalibratedArm, finger_yaw_miss_rad

TARGETS = [[x, y, z] for x in (-0.15, 0.0, 0.2) for y in (0.12, 0.25) for z in (0.03, 0.15)]


@pytest.fixture(scope="module")
def calibrated():
    nominal = load_arm("rx200")
    calibration = ArmCalibration(np.radians([0.0, 1.5, -1.8, 1.2, 0.7]), np.array([0.0, 0.035, 0.07, 0.19, 0.0]),
                                 np.array([0.0, 0.026, 0.05, 0.13, 0.0]), np.array([0.004, -0.003, 0.002, 0.012, 0.0, 0.0]),
                                 np.array([0.0, 0.0, 0.0008, -0.0009, 0.0005, 0.0]))
    return CalibratedArm(nominal, calibration)


def test_no_calibration_is_the_nominal_model():
    nominal = load_arm("rx200")
    arm = CalibratedArm(nominal)
    q = nominal.ik(TARGETS[0], pitch=np.pi / 2)
    assert np.array_equal(arm.ik(TARGETS[0], pitch=np.pi / 2), q) and np.array_equal(arm.fk(q), nominal.fk(q))
    assert arm.joint_names == nominal.joint_names and arm.T_world_base is nominal.T_world_base


def test_ik_meets_the_calibrated_fk(calibrated):
    nominal = calibrated.nominal
    for target in TARGETS:
        q = calibrated.ik(target, pitch=np.pi / 2, yaw=0.0)
        assert np.linalg.norm(calibrated.fk(q)[:3, 3] - target) < 2e-5
        assert abs(calibrated.pitch_of(q) - np.pi / 2) < 2e-4
        q_nominal = nominal.ik(target, pitch=np.pi / 2, yaw=0.0)
        assert np.linalg.norm(calibrated.fk(q_nominal)[:3, 3] - target) > 0.01  # the nominal joints miss by cm


@pytest.mark.parametrize("yaw_deg", [0.0, 20.0, -35.0, 60.0])
def test_ik_turns_the_fingers_to_the_block_on_the_calibrated_arm(yaw_deg):
    # A rig at its extremes: the base turned 1 deg and wrist_rotate's zero 2 deg (adding up, top-down) turn the real fingers
    # off the nominal IK's yaw; the calibrated IK meets the yaw asked for (mod 90 degrees, as a block's faces repeat)
    # on the calibrated FK, single and batched. Before: ~3 deg off (it corrected position and pitch only).
    yaw = np.radians(yaw_deg)
    nominal = load_arm("rx200")
    calibrated = CalibratedArm(nominal, ArmCalibration(np.radians([0.0, 1.5, -1.8, 1.2, -2.0]), np.array([0.0, 0.035, 0.07, 0.19, 0.0]),
                                                       np.array([0.0, 0.026, 0.05, 0.13, 0.0]),
                                                       np.array([0.004, -0.003, 0.002, np.radians(1.0), 0.0, 0.0])))
    assert abs(finger_yaw_miss_rad(nominal.fk(nominal.ik(TARGETS[3], pitch=np.pi / 2, yaw=yaw)), yaw)) < 1e-6  # the convention
    assert abs(finger_yaw_miss_rad(calibrated.fk(nominal.ik(TARGETS[3], pitch=np.pi / 2, yaw=yaw)), yaw)) > np.radians(2.0)
    for target in TARGETS:
        q = calibrated.ik(target, pitch=np.pi / 2, yaw=yaw)
        assert abs(finger_yaw_miss_rad(calibrated.fk(q), yaw)) < 2e-4
        assert np.linalg.norm(calibrated.fk(q)[:3, 3] - target) < 2e-5
    q, ok = calibrated.ik_batch(np.array(TARGETS), pitch=np.pi / 2, yaw=yaw)
    assert ok.all()
    assert max(abs(finger_yaw_miss_rad(T, yaw)) for T in calibrated.fk(q)) < 2e-4


def test_batch_and_pose_ik(calibrated):
    q, ok = calibrated.ik_batch(np.array(TARGETS), pitch=np.pi / 2, yaw=0.0)
    assert ok.all()
    assert np.linalg.norm(calibrated.fk(q)[:, :3, 3] - np.array(TARGETS), axis=1).max() < 2e-5
    goal = calibrated.fk(calibrated.nominal.ik([0.1, 0.2, 0.1], pitch=1.0))
    q_pose = calibrated.ik_pose(goal)
    assert np.linalg.norm(calibrated.fk(q_pose)[:3, 3] - goal[:3, 3]) < 2e-5
    assert np.abs(calibrated.fk(q_pose)[:3, :3] - goal[:3, :3]).max() < 2e-3


def test_swapping_the_calibration_is_seen_by_holders(calibrated):
    arm = CalibratedArm(calibrated.nominal)
    held = arm  # a planner holding the station's model
    before = held.ik(TARGETS[1], pitch=np.pi / 2)
    arm.set_calibration(calibrated.calibration)
    assert np.linalg.norm(held.ik(TARGETS[1], pitch=np.pi / 2) - before) > 0.01
    arm.set_calibration(None)
    assert np.array_equal(held.ik(TARGETS[1], pitch=np.pi / 2), before)
