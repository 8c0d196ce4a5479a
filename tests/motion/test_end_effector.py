"""One end-effector object per gripper type decides what the planners, skills, station and job registry used to
decide by comparing the type's string: how deep a block is held, the lowest approach pitch and grasp, the body
the clearance checks keep off the board, side grasps, and what a missed grasp means."""

from __future__ import annotations

import math

import pytest

from armlab.errors import InvalidInput
from armlab.kinematics.arm_model import load_arm
from armlab.motion.end_effector import END_EFFECTORS, FINGERS, SUCTION, end_effector
from armlab.motion.pick_place import plan_pick
from armlab.motion_config import MotionConfig
from armlab.tasks.registry import unsupported_reason
from armlab.workcell.rig import GRIPPER_TYPES

CONFIG = MotionConfig(grasp_depth_m=0.015, pad_reach_m=0.009, suction_press_m=0.002, top_down_pitch_rad=math.pi / 2)


def test_every_gripper_type_a_workcell_may_name_has_its_end_effector():
    assert set(END_EFFECTORS) == set(GRIPPER_TYPES)
    assert end_effector("suction") is SUCTION and end_effector(FINGERS) is FINGERS


@pytest.mark.parametrize("kind", ["magnet", "", None, 3, "Fingers"])
def test_an_unknown_kind_is_refused_with_the_known_ones(kind):
    with pytest.raises(InvalidInput, match="fingers, suction"):
        end_effector(kind)


def test_fingers_hold_a_block_between_the_pads_and_a_cup_on_its_top():
    assert FINGERS.held_below_top_m(CONFIG, 0.038) == pytest.approx(0.015)  # the grasp depth
    assert FINGERS.held_below_top_m(CONFIG, 0.020) == pytest.approx(0.011)  # a small block: the pads stay off the board
    assert SUCTION.held_below_top_m(CONFIG, 0.038) == pytest.approx(0.002)  # pressed into the seal, whatever the edge
    assert FINGERS.lowest_grasp_m(CONFIG) == pytest.approx(0.009) and SUCTION.lowest_grasp_m(CONFIG) == 0.0
    assert FINGERS.lowest_pitch_rad(CONFIG) == 0.0 and SUCTION.lowest_pitch_rad(CONFIG) == pytest.approx(math.pi / 2)
    assert FINGERS.holds_by_sides and not SUCTION.holds_by_sides
    assert FINGERS.has_palm and not SUCTION.has_palm
    assert FINGERS.has_heading and not SUCTION.has_heading
    assert "fingers" in FINGERS.missed_grasp and "seal" in SUCTION.missed_grasp


def test_the_plan_follows_the_end_effector_it_is_given():
    arm = load_arm("rx200")
    home = arm.home_rad
    fingers = plan_pick(arm, home, [0.0, 0.2, 0.038], 0.0, CONFIG, 0.038, tool=FINGERS)
    cup = plan_pick(arm, home, [0.0, 0.2, 0.038], 0.0, CONFIG, 0.038, tool="suction")
    assert fingers[0].name == "open before pick" and cup[0].name == "vacuum off before pick"
    grasp_z = [float(arm.fk(steps[2].trajectory.positions_rad[-1])[2, 3]) for steps in (fingers, cup)]
    assert grasp_z[0] == pytest.approx(0.038 - 0.015, abs=1e-3) and grasp_z[1] == pytest.approx(0.038 - 0.002, abs=1e-3)


def test_a_job_that_needs_side_grasps_names_the_end_effectors_that_give_them():
    reason = unsupported_reason("to_the_sky", "ur3_suction")
    assert reason is not None and "fingers" in reason and "suction" in reason and "side grasps" in reason
    assert unsupported_reason("to_the_sky", "rx200_armlab") is None
    assert unsupported_reason("pick_sort", "ur3_suction") is None
