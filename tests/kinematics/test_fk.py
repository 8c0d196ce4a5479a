"""Forward kinematics: PoX vs DH vs closed form, the official check points, frames, joint frames."""

import doctest

import numpy as np
import pytest

import armlab.kinematics.arm_model
import armlab.kinematics.dh
import armlab.kinematics.rx200_geometry
import armlab.kinematics.screws

CHECK_POINTS_MM = [
    ([0.0, 0.0, 0.0, 0.0, 0.0], [408.575, 0.0, 304.57]),
    ([0.3, -0.2, 0.4, 1.0, 0.5], [251.0, 77.7, 123.0]),
]


def base_position(arm, T_world):
    return (np.linalg.inv(arm.T_world_base) @ T_world)[..., :3, 3]


@pytest.mark.parametrize("module", [armlab.kinematics.screws, armlab.kinematics.dh, armlab.kinematics.rx200_geometry, armlab.kinematics.arm_model])
def test_docstring_examples_hold(module):
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


@pytest.mark.parametrize("q, expected_mm", CHECK_POINTS_MM)
def test_official_check_points_in_base_frame(rx200, q, expected_mm):
    # The published values have one decimal (the second gives y = 77.646 mm vs the quoted 77.7).
    for method in (rx200.fk, rx200.fk_pox, rx200.fk_dh):
        position_mm = base_position(rx200, method(np.array(q))) * 1000.0
        assert np.allclose(position_mm, expected_mm, atol=0.06), (method.__name__, position_mm)


def test_home_pose_in_world_frame_faces_plus_y(rx200):
    # DESIGN §3: world_x = -base_y, world_y = base_x; the arm faces +y, approach axis along +y.
    pose = rx200.fk(np.zeros(5))
    assert np.allclose(pose[:3, 3], [0.0, 0.408575, 0.30457], atol=1e-12)
    assert np.allclose(pose[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)


def test_dh_pox_and_closed_form_agree_on_10000_random_joint_vectors(rx200):
    rng = np.random.default_rng(42)
    q = rng.uniform(rx200.lower_rad, rx200.upper_rad, size=(10_000, 5))
    pox, dh, closed = rx200.fk_pox(q), rx200.fk_dh(q), rx200.fk(q)
    assert np.abs(pox[:, :3, 3] - dh[:, :3, 3]).max() < 1e-5  # < 0.01 mm
    assert np.abs(pox[:, :3, 3] - closed[:, :3, 3]).max() < 1e-5
    assert np.abs(pox[:, :3, :3] - dh[:, :3, :3]).max() < 1e-9
    assert np.abs(pox[:, :3, :3] - closed[:, :3, :3]).max() < 1e-9


def test_scalar_and_batch_fk_agree(rx200, ur3):
    rng = np.random.default_rng(3)
    for arm in (rx200, ur3):
        q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(50, arm.dof))
        batch = arm.fk(q)
        assert batch.shape == (50, 4, 4)
        for i in range(50):
            assert np.allclose(arm.fk(q[i]), batch[i], atol=1e-12)
            assert np.allclose(arm.fk(tuple(q[i])), batch[i], atol=1e-12)


def test_pitch_is_the_sum_of_the_pitch_joints(rx200):
    # DESIGN §4: gripper pitch below horizontal = q2 + q3 + q4; +pi/2 points straight down.
    q = np.array([0.4, 0.3, 0.5, np.pi / 2 - 0.8, 0.0])
    pose = rx200.fk(q)
    assert np.allclose(pose[:3, 0], [0.0, 0.0, -1.0], atol=1e-12)
    assert rx200.pitch_of(q) == pytest.approx(np.pi / 2)


def test_ur3_official_dh_zero_pose(ur3):
    # UR's DH at q = 0: tool flange at (a2 + a3, -(d4 + d6), d1 - d5); approach axis (flange z) = -y;
    # the suction cup's lip (the tool point) 50 mm beyond the flange along it.
    pose = ur3.fk(np.zeros(6))
    assert np.allclose(pose[:3, 3], [-0.4569, -0.19425 - 0.050, 0.06655], atol=1e-12)
    assert np.allclose(pose[:3, 0], [0.0, -1.0, 0.0], atol=1e-12)


def test_joint_frames_follow_the_urdf_origins(rx200):
    frames = rx200.joint_frames(np.zeros(5))
    assert frames.shape == (6, 4, 4)
    base = base_position(rx200, frames)
    expected = np.cumsum([[0, 0, 0.06566], [0, 0, 0.03891], [0.05, 0, 0.2], [0.2, 0, 0], [0.065, 0, 0], [0.093575, 0, 0]], axis=0)
    assert np.allclose(base, expected, atol=1e-12)


def test_joint_frames_end_at_the_gripper_and_move_with_the_joints(rx200, ur3):
    rng = np.random.default_rng(5)
    for arm in (rx200, ur3):
        q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(200, arm.dof))
        frames = arm.joint_frames(q)
        assert frames.shape == (200, arm.dof + 1, 4, 4)
        assert np.allclose(frames[:, -1], arm.fk(q), atol=1e-12)
        assert np.allclose(arm.joint_frames(q[7]), frames[7], atol=1e-12)
    # the elbow moves when the shoulder does; the waist and shoulder origins never move
    frames = rx200.joint_frames(np.array([[0, 0, 0, 0, 0], [0.5, 0.7, 0, 0, 0.0]]))
    assert np.allclose(frames[0, :2, :3, 3], frames[1, :2, :3, 3])
    elbow_world = frames[1, 2, :3, 3]
    assert elbow_world[2] < frames[0, 2, 2, 3]  # shoulder forward pitches the elbow down


def test_joint_frames_of_one_configuration_equal_the_batch(rx200, ur3):
    """One configuration takes its own path on urdf_origins arms (every joint's exponential at once): the same
    frames as the batch path, at every joint."""
    rng = np.random.default_rng(11)
    for arm in (rx200, ur3):
        q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(300, arm.dof))
        batch = arm.joint_frames(q)
        single = np.array([arm.joint_frames(one) for one in q])
        assert single.shape == batch.shape
        assert np.allclose(single, batch, atol=1e-12, rtol=0.0)
        assert np.allclose(single[:, -1], arm.fk(q), atol=1e-12)


@pytest.mark.parametrize("bad", [[0.0, 0.0, np.nan, 0.0, 0.0], [0.0] * 4, [[0.0] * 6], "abc", [0.0, 0.0, np.inf, 0.0, 0.0]])
def test_fk_rejects_bad_joint_vectors(rx200, bad):
    with pytest.raises(ValueError):
        rx200.fk(bad)


def test_limits_helpers(rx200):
    assert rx200.within_limits(rx200.home_rad) and rx200.within_limits(rx200.sleep_rad)
    assert not rx200.within_limits([0.0, 2.0, 0.0, 0.0, 0.0])  # shoulder beyond 113 deg
    clipped = rx200.clip_to_limits([[4.0, 2.5, -3.0, 0.0, 0.0]])
    assert np.allclose(clipped, [[np.pi, np.radians(113), np.radians(-108), 0.0, 0.0]])
    assert rx200.within_limits(clipped)
