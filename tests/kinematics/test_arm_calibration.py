"""The arm calibration's fit (armlab.kinematics.arm_calibration): on synthetic poses drawn from a known rig it
recovers the joint offsets, compliance, base correction and link lengths; bad inputs are refused."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.kinematics.arm_calibration import (
    ArmCalibration,
    ArmCalibrationError,
    calibrated_fk,
    chain_fk,
    fit_arm,
    gravity_torques,
    offset_joints,
)

MARKER_M = np.array([-0.088575, 0.0, 0.0181])  # the RX200 workcell's gripper tag, in the gripper-point frame


@pytest.fixture(scope="module")
def arm():
    return load_arm("rx200")


def poses(arm, count: int = 18) -> np.ndarray:
    """Commanded joints over the board: level to pitched 0.8 rad down, wrist_rotate varied."""
    rng = np.random.default_rng(3)
    out = []
    while len(out) < count:
        target = [rng.uniform(-0.2, 0.2), rng.uniform(0.16, 0.36), rng.uniform(0.08, 0.22)]
        try:
            q = arm.ik(target, pitch=rng.choice([0.0, 0.4, 0.8]), q_seed=arm.home_rad)
        except ValueError:
            continue
        q[-1] = rng.uniform(-0.4, 0.4)
        out.append(q)
    return np.array(out)


def drawn(arm, seed: int) -> ArmCalibration:
    rng = np.random.default_rng(seed)
    offsets = np.radians(rng.uniform(-2, 2, arm.dof))
    offsets[0] = 0.0  # the waist's zero is the base's yaw
    lengths = np.zeros(arm.dof + 1)
    lengths[2:5] = rng.uniform(-0.001, 0.001, 3)
    base = np.array([*rng.uniform(-0.005, 0.005, 3), np.radians(rng.uniform(-1, 1)), 0.0, 0.0])
    compliance = np.array([0.0, 0.035, 0.07, 0.19, 0.0]) * rng.uniform(0.8, 1.2, arm.dof)
    return ArmCalibration(offsets, compliance, 0.7 * compliance, base, lengths)


def marker_points(arm, truth: ArmCalibration, q: np.ndarray) -> np.ndarray:
    T = calibrated_fk(arm, truth, q)
    return T[:, :3, :3] @ MARKER_M + T[:, :3, 3]


def readings(arm, truth: ArmCalibration, q: np.ndarray) -> np.ndarray:
    return q + truth.servo_compliance_rad_per_nm * gravity_torques(arm, q)


def test_chain_fk_is_the_nominal_fk(arm):
    q = np.random.default_rng(0).uniform(-1, 1, (20, arm.dof))
    assert np.abs(chain_fk(arm, q) - arm.fk(q)).max() < 1e-12


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fit_recovers_the_drawn_rig(arm, seed):
    truth = drawn(arm, seed)
    q = poses(arm)
    noise = np.random.default_rng(seed + 10).normal(0.0, 0.0003, (len(q), 3))  # 0.3 mm: the tag in the depth camera
    fit = fit_arm(arm, q, readings(arm, truth, q), marker_points(arm, truth, q) + noise, MARKER_M)
    assert fit.residual_before_mm > 5.0 and fit.residual_mm < 0.6
    # stated tolerances: offsets 0.4 deg, base 1 mm and 0.2 deg, compliance 20 %, link lengths 1 mm; the top-down
    # gripper point within 2 mm of the truth's. wrist_rotate's offset is not fitted (the tag 18 mm off its axis: in the
    # simulation's sightings it came out 6 deg wrong): it stays 0
    assert np.degrees(np.abs(fit.joint_offset_rad - truth.joint_offset_rad))[:4].max() < 0.4
    assert fit.joint_offset_rad[4] == 0.0
    assert np.abs(fit.base_correction[:3] - truth.base_correction[:3]).max() < 0.001
    assert np.degrees(abs(fit.base_correction[3] - truth.base_correction[3])) < 0.2  # 0.1 with wrist_rotate fitted
    loaded = [1, 2, 3]
    assert np.all(np.abs(fit.compliance_rad_per_nm[loaded] / truth.compliance_rad_per_nm[loaded] - 1.0) < 0.2)
    assert np.allclose(fit.servo_compliance_rad_per_nm, truth.servo_compliance_rad_per_nm, atol=1e-9)
    # what matters: where a top-down gripper point lands, over the board
    q_down = np.array([arm.ik([x, y, z], pitch=np.pi / 2) for x in (-0.15, 0.0, 0.15) for y in (0.15, 0.28) for z in (0.03, 0.15)])
    miss = np.linalg.norm(calibrated_fk(arm, fit, q_down)[:, :3, 3] - calibrated_fk(arm, truth, q_down)[:, :3, 3], axis=1)
    assert np.abs(fit.length_delta_m - truth.length_delta_m).max() < 0.001
    assert miss.max() < 0.002


def test_offsets_the_marker_cannot_see_are_not_fitted(arm):
    # a joint whose axis passes near the marker (wrist_rotate, 18 mm) moves it 0.3 mm a degree: not fitted; the
    # others (and the waist, the base's yaw) are
    assert offset_joints(arm, MARKER_M).tolist() == [False, True, True, True, False]
    assert offset_joints(arm).tolist() == [False, True, True, True, True]


def test_too_few_poses_refused(arm):
    truth, q = drawn(arm, 0), poses(arm, 11)
    with pytest.raises(ArmCalibrationError, match="at least 12 poses"):
        fit_arm(arm, q, q, marker_points(arm, truth, q), MARKER_M)


def test_nan_refused(arm):
    truth, q = drawn(arm, 0), poses(arm)
    seen = marker_points(arm, truth, q)
    seen[4, 1] = np.nan
    with pytest.raises(ArmCalibrationError, match="NaN"):
        fit_arm(arm, q, q, seen, MARKER_M)


def test_fit_no_better_than_nominal_refused(arm):
    q = poses(arm)
    T = arm.fk(q)
    exact = T[:, :3, :3] @ MARKER_M + T[:, :3, 3]  # the arm is exactly nominal: nothing to improve
    with pytest.raises(ArmCalibrationError, match="no better than the nominal"):
        fit_arm(arm, q, q, exact, MARKER_M)


def test_round_trip_and_bad_stored_rows(arm):
    truth = drawn(arm, 1)
    back = ArmCalibration.from_dict(truth.to_dict(), arm.dof)
    assert np.allclose(back.joint_offset_rad, truth.joint_offset_rad) and np.allclose(back.length_delta_m, truth.length_delta_m)
    broken = truth.to_dict()
    broken["joint_offset_rad"] = [0.0, float("nan"), 0, 0, 0]
    with pytest.raises(ArmCalibrationError):
        ArmCalibration.from_dict(broken, arm.dof)
