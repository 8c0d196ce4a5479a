"""Closed-form RX200 IK: round trips, solution choice, pitch search, yaw alignment, unreachable targets."""

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from armlab.kinematics import Unreachable

DOWN = math.pi / 2
# RX200 geometry from config/arms/rx200.yaml, typed in by hand so the expectations below do not come
# from the solver: shoulder axis height, shoulder->elbow at q = 0 (urdf_origins.elbow), forearm, tool.
SHOULDER_Z_M = 0.10457
UPPER_ARM_M = math.hypot(0.05, 0.2)
UPPER_ARM_ELEVATION_RAD = math.atan2(0.2, 0.05)  # 75.96 deg: the upper arm is vertical at shoulder = beta - pi/2
FOREARM_M = 0.2
TOOL_M = 0.158575


def physical_pitch(arm, poses):
    """Approach axis below the horizontal, in the vertical plane through the base axis and the target."""
    approach = poses[:, :3, 0]
    radial = poses[:, :2, 3] - arm.T_world_base[:2, 3]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    return np.arctan2(-approach[:, 2], np.sum(approach[:, :2] * radial, axis=1))


def valid_random_configs(arm, count, seed):
    """FK targets of random in-limit joints whose joints all stay above the board (z >= 0)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(count, arm.dof))
    above = np.all(arm.joint_frames(q)[:, :, 2, 3] >= 0.0, axis=1)
    return q[above]


def leaning_back(q):
    """Shoulder past vertical: the upper arm leans back over the base (q (N, 5) -> (N,) bool)."""
    return np.asarray(q)[:, 1] < UPPER_ARM_ELEVATION_RAD - math.pi / 2


def over_the_back(arm, q):
    """The gripper point lies behind the base axis, seen from where the waist faces: the arm reaches
    over the base to a target behind it (waist = the target's direction + pi). q (N, 5) -> (N,) bool."""
    q = np.asarray(q)
    point = arm.fk(q)[:, :2, 3] - arm.T_world_base[:2, 3]
    facing = q[:, 0] + math.atan2(arm.T_world_base[1, 0], arm.T_world_base[0, 0])  # waist in the world
    return point[:, 0] * np.cos(facing) + point[:, 1] * np.sin(facing) < 0.0


def test_batch_round_trip_100000_targets(rx200):
    # Every in-limit, above-board sample is kept, the arm leaning back over the base included.
    q = valid_random_configs(rx200, 150_000, seed=11)[:100_000]
    assert q.shape[0] == 100_000
    assert leaning_back(q).sum() > 50_000 and over_the_back(rx200, q).sum() > 30_000
    poses = rx200.fk(q)
    targets, pitch = poses[:, :3, 3], physical_pitch(rx200, poses)
    solution, ok = rx200.ik_batch(targets, pitch)
    assert ok.all(), f"{(~ok).sum()} unsolved"
    reached = rx200.fk(solution)
    assert np.abs(reached[:, :3, 3] - targets).max() < 1e-9
    assert np.allclose(physical_pitch(rx200, reached), pitch, atol=1e-6)
    assert rx200.within_limits(solution)
    assert np.all(rx200.joint_frames(solution)[:, :, 2, 3] >= -1e-9)


def test_scalar_matches_batch(rx200):
    q = valid_random_configs(rx200, 400, seed=12)
    poses = rx200.fk(q)
    targets, pitch = poses[:, :3, 3], physical_pitch(rx200, poses)
    batch, ok = rx200.ik_batch(targets, pitch)
    assert ok.all()
    for i in range(len(targets)):
        assert np.allclose(rx200.ik(targets[i], pitch=float(pitch[i])), batch[i], atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5))
def test_seeded_with_an_elbow_up_solution_returns_it(rx200, fractions):
    q = rx200.lower_rad + np.array(fractions) * (rx200.upper_rad - rx200.lower_rad)
    elbow_up = q[2] > -math.atan2(0.2, 0.05)
    above = np.all(rx200.joint_frames(q)[:, 2, 3] >= 0.0)
    pose = rx200.fk(q)
    radius = np.hypot(*pose[:2, 3])
    if not (elbow_up and above and radius > 1e-3):
        return
    pitch = float(physical_pitch(rx200, pose[None])[0])
    solution = rx200.ik(pose[:3, 3], pitch=pitch, q_seed=q)
    assert np.allclose(solution, q, atol=1e-7)  # the seed itself is the closest valid solution


def test_on_the_base_axis_the_waist_follows_the_seed(rx200):
    # Pointing straight up above the base: every waist angle works, so the seed's is kept.
    target = [0.0, 0.0, 0.45]
    for waist_seed in (-2.0, 0.0, 1.0, 2.5):
        seed = np.array([waist_seed, 0.0, 0.0, 0.0, 0.0])
        solution = rx200.ik(target, pitch=-DOWN, q_seed=seed)
        assert solution[0] == pytest.approx(waist_seed)
        assert np.allclose(rx200.fk(solution)[:3, 3], target, atol=1e-9)


def test_default_solution_is_elbow_up_and_facing_the_target(rx200):
    solution = rx200.ik([-0.15, 0.2, 0.03])
    assert solution[0] == pytest.approx(math.atan2(0.15, 0.2))  # waist turns toward the target
    frames = rx200.joint_frames(solution)
    shoulder, elbow, wrist = frames[1, :3, 3], frames[2, :3, 3], frames[3, :3, 3]
    along = (wrist - shoulder) / np.linalg.norm(wrist - shoulder)
    offset = (elbow - shoulder) - np.dot(elbow - shoulder, along) * along
    assert offset[2] > 0.0  # the elbow sits above the shoulder-wrist line


def test_pitch_none_prefers_straight_down(rx200):
    q, pitch = rx200.ik_with_pitch([0.1, 0.25, 0.02])
    assert pitch == DOWN
    assert np.allclose(rx200.fk(q)[:3, 0], [0.0, 0.0, -1.0], atol=1e-9)


@pytest.mark.parametrize("target", [[0.0, 0.45, 0.02], [0.3, 0.35, 0.04], [-0.42, -0.1, 0.0]])
def test_pitch_none_finds_the_steepest_reachable_pitch_far_away(rx200, target):
    with pytest.raises(Unreachable):
        rx200.ik(target, pitch=DOWN)
    q, pitch = rx200.ik_with_pitch(target)
    assert pitch < DOWN
    assert np.allclose(rx200.fk(q)[:3, 3], target, atol=1e-9)
    assert rx200.pitch_of(q) == pytest.approx(pitch, abs=1e-9)
    with pytest.raises(Unreachable):
        rx200.ik(target, pitch=pitch + 1e-3)  # a little steeper is no longer reachable


def test_batch_pitch_search_matches_scalar(rx200):
    rng = np.random.default_rng(4)
    targets = np.column_stack([rng.uniform(-0.5, 0.5, 300), rng.uniform(-0.175, 0.475, 300), rng.uniform(0.0, 0.1, 300)])
    batch, ok = rx200.ik_batch(targets)
    for i in range(len(targets)):
        try:
            q = rx200.ik(targets[i])
        except Unreachable:
            assert not ok[i]
            continue
        assert ok[i]
        assert rx200.pitch_of(batch[i]) == pytest.approx(rx200.pitch_of(q), abs=1e-6)
        assert np.allclose(rx200.fk(batch[i])[:3, 3], targets[i], atol=1e-9)
    assert ok.mean() > 0.9  # nearly the whole board is pickable with the pitch search


def face_angle_error(finger_axis_xy, yaw):
    """Angle between a horizontal finger axis and the nearest block face normal (mod pi/2)."""
    angle = math.atan2(finger_axis_xy[1], finger_axis_xy[0]) - yaw
    return abs((angle + math.pi / 4) % (math.pi / 2) - math.pi / 4)


@settings(max_examples=150, deadline=None)
@given(
    st.floats(-0.2, 0.2), st.floats(0.12, 0.3), st.floats(-math.pi, math.pi), st.floats(-3 * math.pi / 4, 3 * math.pi / 4)
)
def test_yaw_aligns_fingers_with_minimal_wrist_motion(rx200, x, y, yaw, wrist_seed):
    seed = np.array([0.0, 0.0, 0.0, 0.0, wrist_seed])
    q = rx200.ik([x, y, 0.02], pitch=DOWN, yaw=yaw, q_seed=seed)
    finger_axis = rx200.fk(q)[:3, 1]
    assert abs(finger_axis[2]) < 1e-9
    assert face_angle_error(finger_axis[:2], yaw) < 1e-9
    # documented convention: pointing down, the fingers close along world angle (waist - wrist_rotate)
    assert face_angle_error([math.cos(q[0] - q[4]), math.sin(q[0] - q[4])], yaw) < 1e-9
    equivalents = [q[0] - yaw + k * math.pi / 2 for k in range(-8, 9)]
    allowed = [v for v in equivalents if rx200.lower_rad[4] <= v <= rx200.upper_rad[4]]
    assert abs(q[4] - wrist_seed) <= min(abs(v - wrist_seed) for v in allowed) + 1e-9
    assert abs(q[4] - wrist_seed) <= math.pi / 4 + 1e-9


def test_yaw_with_a_tilted_gripper_aligns_the_projected_finger_axis(rx200):
    for yaw in (0.0, 0.4, -1.0, 2.0):
        q = rx200.ik([0.2, 0.3, 0.05], pitch=1.0, yaw=yaw)
        finger_axis = rx200.fk(q)[:3, 1]
        assert face_angle_error(finger_axis[:2], yaw) < 1e-9


def test_yaw_none_keeps_the_seed_wrist(rx200):
    seed = np.array([0.0, 0.0, 0.0, 0.0, 0.7])
    assert rx200.ik([0.0, 0.3, 0.05], q_seed=seed)[4] == pytest.approx(0.7)
    assert rx200.ik([0.0, 0.3, 0.05])[4] == 0.0


def test_batch_yaw_matches_scalar(rx200):
    rng = np.random.default_rng(9)
    targets = np.column_stack([rng.uniform(-0.2, 0.2, 200), rng.uniform(0.1, 0.3, 200), np.full(200, 0.03)])
    yaws = rng.uniform(-math.pi, math.pi, 200)
    seed = np.array([0.0, 0.0, 0.0, 0.0, 1.0])
    batch, ok = rx200.ik_batch(targets, DOWN, yaws, q_seed=seed)
    assert ok.all()
    for i in range(200):
        assert np.allclose(batch[i], rx200.ik(targets[i], DOWN, yaws[i], q_seed=seed), atol=1e-9)


# ---------------------------------------------------------------- over the back (waist + pi, shoulder past vertical)

# In-limit joint vectors with every joint above the board, the shoulder past vertical and the gripper
# point behind the base axis: the arm reaches over the base to a target behind it.
LEANING_BACK_Q = [
    [0.5, -1.5, 1.2, 2.1, 0.3],  # issue 8's example: gripper 7 cm above the board, just behind the base
    [0.5, -1.5, 1.2, DOWN + 0.3, 0.3],  # the same arm pointing straight down
    [2.92, -1.88, -0.69, 1.25, 1.17],  # far over the back, pointing up: only the half-turned waist reaches it
    [1.34, -1.79, -0.99, 1.95, 0.37],  # likewise
]
# Of those, the targets no solution facing the target reaches (only waist = target direction + pi)
ONLY_OVER_THE_BACK_Q = LEANING_BACK_Q[2:]


def world_approach(arm, target, pitch):
    """The approach axis a pitch means in the world: `pitch` below the horizontal, in the vertical plane
    through the base axis and the target, 0 = pointing away from the base axis."""
    radial = np.asarray(target[:2], float) - arm.T_world_base[:2, 3]
    radial /= np.linalg.norm(radial)
    return np.array([math.cos(pitch) * radial[0], math.cos(pitch) * radial[1], -math.sin(pitch)])


@pytest.mark.parametrize("q", LEANING_BACK_Q)
def test_target_of_an_arm_leaning_back_over_the_base_is_solved(rx200, q):
    q = np.array(q)
    assert rx200.within_limits(q) and rx200.joint_frames(q)[:, 2, 3].min() >= 0.0
    assert leaning_back(q[None])[0] and over_the_back(rx200, q[None])[0]
    pose = rx200.fk(q)
    target, pitch = pose[:3, 3], float(physical_pitch(rx200, pose[None])[0])
    for seed in (None, q, rx200.sleep_rad):
        solution = rx200.ik(target, pitch=pitch, q_seed=seed)
        reached = rx200.fk(solution)
        assert np.abs(reached[:3, 3] - target).max() < 1e-9
        assert np.allclose(reached[:3, 0], world_approach(rx200, target, pitch), atol=1e-9)
        assert rx200.within_limits(solution)
        assert rx200.joint_frames(solution)[:, 2, 3].min() >= -1e-9
    # seeded with the arm's own pose, that pose is the closest solution: the over-the-back one
    assert np.allclose(rx200.ik(target, pitch=pitch, q_seed=q), q, atol=1e-9)
    batch, ok = rx200.ik_batch(target[None], pitch, q_seed=q)
    assert ok[0] and np.allclose(batch[0], q, atol=1e-9)


@pytest.mark.parametrize("q", ONLY_OVER_THE_BACK_Q)
def test_targets_only_reachable_over_the_back_get_the_half_turned_waist(rx200, q):
    q = np.array(q)
    pose = rx200.fk(q)
    target, pitch = pose[:3, 3], float(physical_pitch(rx200, pose[None])[0])
    toward_target = math.atan2(target[1], target[0]) - math.pi / 2  # waist facing the target (base x = world y)
    for seed_waist in (toward_target, 0.0, q[0]):
        seed = np.array([seed_waist, 0.0, 0.0, 0.0, 0.0])
        solution = rx200.ik(target, pitch=pitch, q_seed=seed)
        assert math.cos(solution[0] - toward_target) == pytest.approx(-1.0, abs=1e-9)  # waist = direction + pi
        assert leaning_back(solution[None])[0]
        assert np.abs(rx200.fk(solution)[:3, 3] - target).max() < 1e-9
    q_found, pitch_found = rx200.ik_with_pitch(target)  # the pitch search finds a pitch there too
    assert np.abs(rx200.fk(q_found)[:3, 3] - target).max() < 1e-9
    assert rx200.pitch_of(q_found) == pytest.approx(pitch_found, abs=1e-9)


@pytest.mark.parametrize("yaw", [0.0, 0.3, -1.2, 2.5])
def test_over_the_back_pitch_and_yaw_mean_the_same_in_the_world(rx200, yaw):
    # Straight down over a point just behind the base, the arm leaning back with the waist turned away.
    q = np.array(LEANING_BACK_Q[1])
    target = rx200.fk(q)[:3, 3]
    solution = rx200.ik(target, pitch=DOWN, yaw=yaw, q_seed=q)
    assert np.allclose(solution[:4], q[:4], atol=1e-9)  # the over-the-back branch, as seeded
    reached = rx200.fk(solution)
    assert np.abs(reached[:3, 3] - target).max() < 1e-9
    assert np.allclose(reached[:3, 0], [0.0, 0.0, -1.0], atol=1e-9)  # pi/2 = straight down
    assert face_angle_error(reached[:2, 1], yaw) < 1e-9  # the fingers close across the block's faces
    # tilted and far over the back (pointing up): the pitch is the world pitch, the yaw the world yaw
    q_far = np.array(LEANING_BACK_Q[2])
    far = rx200.fk(q_far)[:3, 3]
    pitch = float(physical_pitch(rx200, rx200.fk(q_far)[None])[0])
    solution = rx200.ik(far, pitch=pitch, yaw=yaw, q_seed=q_far)
    reached = rx200.fk(solution)
    assert np.abs(reached[:3, 3] - far).max() < 1e-9
    assert np.allclose(reached[:3, 0], world_approach(rx200, far, pitch), atol=1e-9)
    assert face_angle_error(reached[:2, 1], yaw) < 1e-9


# ---------------------------------------------------------------- the default choice in front of the arm


def hand_elbow_up_straight_down(x, y, z):
    """Elbow-up joints pointing straight down at world (x, y, z), by plane geometry (RX200, base at the
    world origin with base x = world y): waist toward the target, law of cosines in the arm's plane."""
    waist = math.atan2(-x, y)
    rc, zc = math.hypot(x, y), z + TOOL_M - SHOULDER_Z_M  # wrist centre from the shoulder
    d = math.hypot(rc, zc)
    cos_at_shoulder = (UPPER_ARM_M**2 + d * d - FOREARM_M**2) / (2.0 * UPPER_ARM_M * d)
    elevation = math.atan2(zc, rc) + math.acos(cos_at_shoulder)  # elbow above the shoulder-wrist line
    shoulder = UPPER_ARM_ELEVATION_RAD - elevation
    forearm_down = math.atan2(-(zc - UPPER_ARM_M * math.sin(elevation)), rc - UPPER_ARM_M * math.cos(elevation))
    return [waist, shoulder, forearm_down - shoulder, DOWN - forearm_down, 0.0]


@pytest.mark.parametrize("target", [[0.0, 0.25, 0.05], [-0.15, 0.2, 0.03], [0.2, 0.15, 0.0], [-0.1, 0.3, 0.08], [0.25, 0.05, 0.02]])
def test_default_choice_in_front_matches_hand_computed_elbow_up(rx200, target):
    expected = hand_elbow_up_straight_down(*target)
    for seed in (None, [0.3, 0.2, 0.2, 1.0, 0.0], [-0.5, 0.5, -0.3, 1.4, 0.0]):
        assert np.allclose(rx200.ik(target, q_seed=seed), expected, atol=1e-9)


# (target, pitch, yaw, seed, expected q, pitch used): recorded from ik_rx200 at commit 5935066, before the
# over-the-back review, so the choice among solutions for ordinary targets stays as it was.
RECORDED_CHOICES = [
    ([0.0, 0.25, 0.05], None, None, None, [0.0, 0.10733035489661802, 0.3565698658668497, 1.1068961060314289, 0.0], DOWN),
    ([-0.15, 0.2, 0.03], DOWN, 0.4, None, [0.6435011087932843, 0.1551994960527554, 0.4025892596115861, 1.0130075711305553, 0.24350110879328435], DOWN),
    ([0.2, 0.15, 0.0], DOWN, None, [0.5, 0.3, 0.2, 1.0, 0.0], [-0.9272952180016123, 0.24202742377710784, 0.4536572978452442, 0.8751116051725445, 0.0], DOWN),
    ([0.1, 0.3, 0.1], 1.0, -0.7, [0.0, 0.0, 0.0, 0.0, 1.0], [-0.32175055439664213, -0.029125524460796193, 0.40010121912661356, 0.6290243053341826, 0.44120184698978004], 1.0),  # noqa: E501 (recorded solutions, one per row)
    ([-0.25, 0.3, 0.02], None, 0.2, None, [0.6947382761967034, 0.9344337586237277, -0.9112484291337373, 1.547610997304906, 0.49473827619670363], DOWN),
    ([0.0, 0.45, 0.02], None, None, None, [0.0, 1.1621755319929745, -1.325762094023228, 1.418455513821593, 0.0], 1.2548689517913398),
    ([0.3, 0.35, 0.04], None, 1.2, [-0.6, 0.5, 0.5, 0.5, 0.0], [-0.7086262721276704, 1.1251018020618204, -1.3257623733958492, 1.3630777473927775, -0.3655690415334272], 1.1624171760587485),  # noqa: E501 (recorded solutions, one per row)
    ([0.05, 0.2, 0.25], 0.0, None, None, [-0.24497866312686423, -1.0763128571150116, 1.0437876703254936, 0.03252518678951777, 0.0], 0.0),
    ([-0.1, 0.35, 0.15], 0.3, 0.0, [0.2, 0.0, 0.0, 0.0, -2.0], [0.27829965900511144, -0.025986017415020157, 0.6020144692904488, -0.2760284518754288, -2.3730637415800055], 0.3),  # noqa: E501 (recorded solutions, one per row)
    ([0.15, 0.05, 0.03], DOWN, None, [2.0, 0.0, 0.0, 0.0, 0.0], [-1.2490457723982544, -0.24619481172735647, 0.9032030513283436, 0.9137880871939092, 0.0], DOWN),
]  # fmt: skip


@pytest.mark.parametrize("target, pitch, yaw, seed, expected, pitch_used", RECORDED_CHOICES)
def test_default_choice_in_front_is_unchanged(rx200, target, pitch, yaw, seed, expected, pitch_used):
    q, used = rx200.ik_with_pitch(target, pitch, yaw, seed)
    assert np.allclose(q, expected, atol=1e-9)
    assert used == pytest.approx(pitch_used, abs=1e-9)
    batch, ok = rx200.ik_batch([target], pitch, yaw, q_seed=seed)
    assert ok[0] and np.allclose(batch[0], expected, atol=1e-6)  # the batch search refines the pitch to ~1e-7


@pytest.mark.parametrize(
    "target, pitch, reason",
    [
        ([0.0, 0.7, 0.1], None, "out of reach"),
        ([0.0, 0.7, 0.1], DOWN, "out of reach"),
        ([0.0, 0.0, 0.8], None, "out of reach"),
        ([0.0, -0.45, 0.5], None, "out of reach"),  # behind and above: too far even over the back
        ([0.0, 0.2, -0.01], None, "below the table"),
        ([0.0, 0.35, 0.0], -0.15, "below the table"),  # the wrist would go under the board
        ([0.0, 0.05, 0.3], DOWN, "joint limit (wrist_angle)"),
    ],
)
def test_unreachable_targets_say_why(rx200, target, pitch, reason):
    with pytest.raises(Unreachable) as error:
        rx200.ik(target, pitch=pitch)
    assert isinstance(error.value, ValueError)
    assert error.value.reason == reason
    assert reason in str(error.value)
    _, ok = rx200.ik_batch([target], pitch)
    assert not ok[0]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"position_m": [0.0, float("nan"), 0.1]},
        {"position_m": [0.0, 0.2]},
        {"position_m": [0.0, 0.2, 0.1], "pitch": float("inf")},
        {"position_m": [0.0, 0.2, 0.1], "yaw": float("nan")},
        {"position_m": [0.0, 0.2, 0.1], "q_seed": [0.0, 0.0]},
        {"position_m": "0 0.2 0.1"},
    ],
)
def test_bad_input_is_a_clear_value_error_not_unreachable(rx200, kwargs):
    with pytest.raises(ValueError) as error:
        rx200.ik(**kwargs)
    assert not isinstance(error.value, Unreachable)


def test_batch_rejects_bad_shapes(rx200):
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        rx200.ik_batch(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="pitch"):
        rx200.ik_batch(np.zeros((4, 3)), pitch=np.zeros(3))
    with pytest.raises(ValueError, match="finite"):
        rx200.ik_batch(np.full((2, 3), np.nan))


def test_pitch_search_is_the_steepest_by_brute_force(rx200):
    # Independent of the search: try every pitch on a 0.1-degree grid; none steeper than the one
    # found (beyond the grid spacing) may be reachable, and the one found must be.
    rng = np.random.default_rng(8)
    targets = np.column_stack([rng.uniform(-0.5, 0.5, 150), rng.uniform(-0.175, 0.475, 150), rng.uniform(0.0, 0.15, 150)])
    q, ok = rx200.ik_batch(targets)
    grid = np.arange(-math.pi / 2, math.pi + 1e-9, math.radians(0.1))
    tiled_targets = np.repeat(targets, grid.size, axis=0)
    tiled_pitch = np.tile(grid, len(targets))
    _q, grid_ok = rx200.ik_batch(tiled_targets, tiled_pitch)
    grid_ok = grid_ok.reshape(len(targets), grid.size)
    for i in range(len(targets)):
        if not ok[i]:
            assert not grid_ok[i].any()  # unreachable at every pitch on the grid too
            continue
        found = rx200.pitch_of(q[i])
        steepest_on_grid = np.min(np.abs(grid[grid_ok[i]] - math.pi / 2)) if grid_ok[i].any() else np.inf
        assert abs(found - math.pi / 2) <= steepest_on_grid + 1e-9
    assert ok.sum() > 100


# ------------------------------------------------ the pitch a pose reports is the pitch ik takes (issue 20 item 6)

# In the limits, every joint above the board, the gripper pointing up and back toward the base axis. Its
# approach axis is 102.9 deg below the horizontal seen from the base (world pitch); an asin of the approach
# axis reads -77.1 deg, which asks for the approach pointing up and AWAY from the base: no joint vector
# within the limits reaches that (ik: "shoulder needs 120.3 deg"). Readers of a pose (the status' gripper_pose,
# the vertical segment's held pitch) used that asin, so the arm's own pose came back refused.
UP_AND_BACK_Q = [-1.361, -1.874, -1.511, 2.040, 0.212]


def test_the_pose_of_an_arm_pointing_up_and_back_round_trips_through_its_reported_pitch(rx200):
    from armlab.motion.cartesian import gripper_pitch_rad, plan_vertical_segment
    from armlab.station.telemetry import gripper_pose_from_matrix

    q = np.array(UP_AND_BACK_Q)
    assert rx200.within_limits(q) and rx200.joint_frames(q)[:, 2, 3].min() >= 0.0
    pose = rx200.fk(q)
    expected_pitch = float(physical_pitch(rx200, pose[None])[0])  # the test's own reading: -102.9 deg
    assert math.degrees(expected_pitch) == pytest.approx(-102.94, abs=0.01)
    reported = gripper_pose_from_matrix(pose, rx200.T_world_base[:3, 3])
    for pitch in (reported["pitch_rad"], gripper_pitch_rad(rx200, q)):
        assert pitch == pytest.approx(expected_pitch, abs=1e-9)
        solution = rx200.ik(reported["position_m"], pitch=pitch, q_seed=rx200.home_rad)
        reached = rx200.fk(solution)
        assert np.abs(reached[:3, 3] - pose[:3, 3]).max() < 1e-9
        assert np.abs(reached[:3, 0] - pose[:3, 0]).max() < 1e-9
    # a straight 20 mm rise from that pose keeps it (before: the asin pitch made ik change branch on the way)
    rise = plan_vertical_segment(rx200, q, pose[2, 3] + 0.02)
    ends = rx200.fk(rise.positions_rad[[0, -1]])
    assert ends[1, 2, 3] == pytest.approx(pose[2, 3] + 0.02, abs=1e-6)
    assert np.abs(ends[1, :3, 0] - pose[:3, 0]).max() < 1e-6


@settings(max_examples=120, derandomize=True, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5), st.sampled_from(["home", "own", "sleep"]))
def test_fk_then_ik_at_the_reported_pitch_round_trips_over_in_limit_joints(rx200, fractions, seed_name):
    """Any joint vector within the limits with every joint above the board: its gripper point at the pitch
    its pose reports is solved, to the same position and approach axis (120 derandomised examples)."""
    from armlab.station.telemetry import gripper_pose_from_matrix

    lower, upper = rx200.lower_rad, rx200.upper_rad
    q = lower + np.array(fractions) * (upper - lower)
    assume(rx200.joint_frames(q)[:, 2, 3].min() >= 0.0)
    pose = rx200.fk(q)
    reported = gripper_pose_from_matrix(pose, rx200.T_world_base[:3, 3])
    seed = {"home": rx200.home_rad, "own": q, "sleep": rx200.sleep_rad}[seed_name]
    solution = rx200.ik(reported["position_m"], pitch=reported["pitch_rad"], q_seed=seed)
    reached = rx200.fk(solution)
    assert rx200.within_limits(solution)
    assert np.abs(reached[:3, 3] - pose[:3, 3]).max() < 1e-9
    assert np.abs(reached[:3, 0] - pose[:3, 0]).max() < 1e-9
