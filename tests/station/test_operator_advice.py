"""operator_advice (issue 21, Misleading 5): a click-grab/drop refusal said with what the operator can do, the
direction taken from the planner's own figures; errors it cannot improve are left alone (pure, no station)."""

from __future__ import annotations

import pytest

from armlab.errors import Unreachable
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.operator_advice import advised

FAR = ("no gripper pitch between 90° and 0° reaches (400, 400, 9) mm: target (0.4000, 0.4000, 0.0090) m at pitch 90.0 deg: "
       "out of reach (wrist centre 0.5692 m from the shoulder; the arm spans 0.0062..0.4062 m)")


@pytest.mark.parametrize("text, base_xy_m, expected", [
    (FAR, None, "its wrist would be 569 mm from the shoulder; it reaches 406 mm): click a spot nearer the arm"),
    (FAR.replace("0.5692 m", "0.0031 m"), None, "click a spot farther from the arm's base"),
    ("the gripper at 90° pitch (a suction cup seals only flat on a face) does not reach (0, 100, 9) mm: out of reach",
     (0.0, 0.0), "out of the arm's reach with the suction cup flat on top (100 mm from its base): click a spot within"),
])
def test_out_of_reach_says_which_way(text, base_xy_m, expected):
    better = advised("grab", [0.0, 0.1, 0.0] if base_xy_m else [0.4, 0.4, 0.0], Unreachable(text, "out of reach"), base_xy_m)
    assert isinstance(better, Unreachable) and better.reason == "out of reach"
    assert expected in str(better), str(better)
    assert "wrist centre" not in str(better)


def test_the_board_in_the_way_down_says_to_click_nearer():
    better = advised("drop", [0.0, 0.45, 0.0],
                     UnsafeTrajectory("the fingers would go 4.2 mm into the board (gripper point at z = 9.0 mm) at t = 1.158 s"))
    assert isinstance(better, UnsafeTrajectory)
    assert str(better) == ("drop at (0, 450) mm: the gripper cannot come straight down there; on its way down it would touch "
                           "the board (4.2 mm into it): click a spot nearer the arm")


def test_other_refusals_are_left_alone():
    assert advised("grab", [0.1, 0.2, 0.0], UnsafeTrajectory("descend to grasp: the open fingers would touch the yellow block")) is None
    assert advised("grab", [0.1, 0.2, 0.0], Unreachable("joint limit (waist)", "joint limit")) is None
    assert advised("grab", [0.1, 0.2, 0.0], ValueError("x")) is None
