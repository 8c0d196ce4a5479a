"""Jog steps of the gripper, planned (pure): a Cartesian step keeps the gripper's pitch and yaw within 0.5°
and the gripper point on the asked axis within 1 mm at every sample, or is refused with the reason; pitch
and roll steps turn only what they name. Pitch and yaw are computed here from the FK matrices (the
status' definitions: pitch below the horizontal in the arm's plane, yaw = heading of the closing axis)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armlab.kinematics import Unreachable, load_arm
from armlab.motion.gripper_step import FingerBox, StepRefused, StepSpeeds, plan_gripper_step, yaw_turn_rad

ARM = load_arm("rx200")
SPEEDS = StepSpeeds(0.05, 0.2, 0.5, 2.0)
TOL_M, TOL_RAD = 0.001, math.radians(0.5)
FINGERS = FingerBox(back_m=0.07, reach_m=0.009, half_width_m=0.045, half_height_m=0.012)  # the rx200's open fingers
CLEARANCE_M = 0.003


def pose(q) -> tuple[np.ndarray, float, float]:
    """(position, pitch, yaw) of the gripper at q: pitch in the vertical plane through the base axis."""
    T = ARM.fk(np.asarray(q, float))
    approach, closing, p = T[:3, 0], T[:3, 1], T[:3, 3]
    radial = p[:2] / max(np.linalg.norm(p[:2]), 1e-9)  # the base axis is the world origin (DESIGN §3)
    return p, math.atan2(-approach[2], float(approach[:2] @ radial)), math.atan2(closing[1], closing[0])


def wrap(angle: float) -> float:
    return math.remainder(angle, 2 * math.pi)


START_POSES = {
    "home": np.zeros(5),
    "near the table": ARM.ik([0.0, 0.25, 0.04], pitch=math.pi / 2),
    "to the side": ARM.ik([0.25, 0.15, 0.10], pitch=math.pi / 2, yaw=0.3),
    "over the back": ARM.ik([-0.12, -0.12, 0.15], pitch=math.pi / 2),
    "leaning back": np.array([0.3, -0.5, 0.2, 2.0, 0.4]),
    "tilted": ARM.ik([-0.2, 0.2, 0.15], pitch=0.6),
}
LINEAR = [(axis, sign * 0.01) for axis in "xyz" for sign in (1, -1)]


def assert_step_kept(q_path: np.ndarray, axis: str, amount: float) -> None:
    """Every sample: on the asked motion (1 mm), pitch and yaw kept (0.5°) or changed by the step; a Cartesian
    step that keeps the wrist roll (the gripper level or tilted: the roll cannot hold the yaw) turns the yaw by
    the waist's turn, no more (issue 21)."""
    p0, pitch0, yaw0 = pose(q_path[0])
    follows_waist = axis in "xyz" and abs(q_path[-1][4] - q_path[0][4]) < 1e-9 and abs(wrap(pose(q_path[-1])[2] - yaw0)) > TOL_RAD
    for q in q_path:
        p, pitch, yaw = pose(q)
        if axis in "xyz":
            k = "xyz".index(axis)
            off = np.delete(p - p0, k)
            assert np.abs(off).max() <= TOL_M, f"{axis} step left its line by {np.abs(off).max() * 1000:.2f} mm"
            expected_yaw = yaw0 + (q[0] - q_path[0][0] if follows_waist else 0.0)
            assert abs(wrap(pitch - pitch0)) <= TOL_RAD and abs(wrap(yaw - expected_yaw)) <= TOL_RAD
        else:
            assert np.linalg.norm(p - p0) <= TOL_M, f"{axis} step moved the gripper point"
        if axis == "roll":
            assert abs(wrap(pitch - pitch0)) <= TOL_RAD
    p1, pitch1, _ = pose(q_path[-1])
    if axis in "xyz":
        assert abs((p1 - p0)["xyz".index(axis)] - amount) <= TOL_M
    elif axis == "pitch":
        assert abs(wrap(pitch1 - pitch0 - amount)) <= TOL_RAD
        assert q_path[-1][4] == pytest.approx(q_path[0][4], abs=1e-9), "a pitch step keeps the wrist roll"
    else:
        assert q_path[-1][4] - q_path[0][4] == pytest.approx(amount, abs=1e-9)
        assert np.allclose(q_path[-1][:4], q_path[0][:4], atol=1e-9), "a roll step turns wrist_rotate only"


@pytest.mark.parametrize("start", ["home", "near the table", "to the side", "over the back", "leaning back"])
@pytest.mark.parametrize("axis, amount", LINEAR + [("pitch", 0.1), ("pitch", -0.1), ("roll", 0.2), ("roll", -0.2)])
def test_a_step_moves_only_along_its_axis_and_keeps_pitch_and_yaw(start, axis, amount):
    q0 = START_POSES[start]
    trajectory = plan_gripper_step(ARM, q0, axis, amount, SPEEDS, FINGERS, CLEARANCE_M)
    assert np.allclose(trajectory.positions_rad[0], q0)
    assert_step_kept(trajectory.positions_rad, axis, amount)


def test_z_from_home_keeps_the_wrist_and_the_yaw():
    """The reported defect: a 10 mm -Z step from home turned wrist_rotate 0 -> 90° and the yaw 180° -> 0°."""
    q = np.zeros(5)
    for _ in range(2):
        q = plan_gripper_step(ARM, q, "z", -0.01, SPEEDS, FINGERS, CLEARANCE_M).positions_rad[-1]
    assert abs(q[4]) < 1e-9
    assert abs(wrap(pose(q)[2] - math.pi)) <= TOL_RAD
    assert pose(q)[0][2] == pytest.approx(pose(np.zeros(5))[0][2] - 0.02, abs=TOL_M)


@pytest.mark.parametrize(
    "start, axis, amount, words",
    [
        ("near the table", "z", -0.05, "below"),  # 50 mm down near the table: refused, not 63 mm up
        ("near the table", "roll", math.pi / 4 + 0.1, "at most"),
    ],
)
def test_refusals_say_why(start, axis, amount, words):
    with pytest.raises(ValueError, match=words):
        plan_gripper_step(ARM, START_POSES[start], axis, amount, SPEEDS, FINGERS, CLEARANCE_M)


@pytest.mark.parametrize("start, axis, amount", [("home", "x", 0.025), ("home", "x", -0.025), ("tilted", "x", 0.01), ("tilted", "y", -0.01)])
def test_level_or_tilted_the_yaw_turns_with_the_waist_and_the_wrist_stays(start, axis, amount):
    """Issue 21: an X step from Home (the gripper level) was always refused ("yaw would change by 3.50° …
    wrist_rotate jumps 1.571 rad"); the roll cannot hold the heading of a level or tilted gripper, so the step
    keeps the wrist roll and the pitch, and the yaw turns exactly as the waist does."""
    q0 = START_POSES[start]
    path = plan_gripper_step(ARM, q0, axis, amount, SPEEDS, FINGERS, CLEARANCE_M).positions_rad
    assert np.allclose(path[:, 4], q0[4], atol=1e-9) and abs(path[-1][0] - q0[0]) > math.radians(0.5)
    assert_step_kept(path, axis, amount)
    assert abs(wrap(yaw_turn_rad(ARM, path) - (path[-1][0] - q0[0]))) < TOL_RAD


def test_roll_past_the_wrist_limit_is_refused():
    q = START_POSES["near the table"].copy()
    q[4] = math.radians(175)
    with pytest.raises(StepRefused, match="wrist_rotate"):
        plan_gripper_step(ARM, q, "roll", 0.2, SPEEDS, FINGERS, CLEARANCE_M)


def test_fingers_that_would_touch_the_board_are_refused():
    """Tilted 29° and rolled -47°, 46 mm up: 10 mm down puts the lower open finger into the board (the
    simulation stopped it 2.4 mm short); the gripper point alone would still be 36 mm up."""
    q0 = np.radians([34.2, -11.8, 82.3, -41.8, -47.0])
    with pytest.raises(StepRefused, match="fingers would come down"):
        plan_gripper_step(ARM, q0, "z", -0.01, SPEEDS, FINGERS, CLEARANCE_M)
    plan_gripper_step(ARM, q0, "z", -0.01, SPEEDS, None, CLEARANCE_M)  # the point alone: accepted


def test_a_tilted_gripper_low_over_the_table_is_refused_not_bent_up():
    """A 50 mm -Z step with the gripper tilted near the table must not end higher with another pitch."""
    q0 = ARM.ik([0.0, 0.3, 0.06], pitch=0.3)
    try:
        trajectory = plan_gripper_step(ARM, q0, "z", -0.05, SPEEDS, FINGERS, CLEARANCE_M)
    except Unreachable as error:
        assert str(error)
        return
    assert_step_kept(trajectory.positions_rad, "z", -0.05)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    x=st.floats(-0.3, 0.3), y=st.floats(0.08, 0.35), z=st.floats(0.03, 0.25), pitch=st.floats(0.2, math.pi / 2),
    yaw=st.floats(-math.pi, math.pi), axis=st.sampled_from(["x", "y", "z", "pitch", "roll"]),
    amount=st.floats(-0.05, 0.05).filter(lambda a: abs(a) > 1e-3),
)
def test_property_every_step_is_exact_or_refused_with_a_reason(x, y, z, pitch, yaw, axis, amount):
    try:
        q0 = ARM.ik([x, y, z], pitch=pitch, yaw=yaw)
    except Unreachable:
        return
    if axis in ("pitch", "roll"):
        amount *= 10  # radians: up to 0.5 rad
    try:
        trajectory = plan_gripper_step(ARM, q0, axis, amount, SPEEDS, FINGERS, CLEARANCE_M)
    except ValueError as error:  # Unreachable, StepRefused, a joint limit: all say why
        assert len(str(error)) > 20
        return
    assert_step_kept(trajectory.positions_rad, axis, amount)
    assert ARM.within_limits(trajectory.positions_rad)
    T = ARM.fk(trajectory.positions_rad)
    lowest = (T[:, 2, :3] @ FINGERS.corners_m().T + T[:, 2, 3][:, None]).min()
    assert lowest >= CLEARANCE_M - 1e-9
