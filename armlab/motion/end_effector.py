"""The tool at the arm's end, chosen once per workcell (its `gripper.type`): how it holds a block, how it may
approach one, what its body is for the clearance checks, and what a failed grasp means. Planners, skills, the
station and the job registry ask this object instead of comparing the gripper's type string.

Fingers close on a block's sides, grasp_depth_for(edge) below its top, and may tilt or hold a block from the
side. A suction cup seals on the top face only, so it comes straight down (top-down pitch), presses
suction_press_m into the seal, and has no fingers or palm to keep off the board.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

from armlab.errors import InvalidInput
from armlab.motion.gripper_step import FingerBox
from armlab.motion_config import MotionConfig


class EndEffector(ABC):
    """What the station's tool can do; one immutable instance per kind (FINGERS, SUCTION)."""

    name: ClassVar[str]  # the workcell's gripper.type
    holds_by_sides: ClassVar[bool]  # may hold a block from the side (a tower's upper blocks) and carry it tilted
    release_before_pick: ClassVar[str]  # the plan's first step's name
    missed_grasp: ClassVar[str]  # why a grasp that holds nothing failed, as the operator reads it
    has_palm: ClassVar[bool]  # a palm behind the fingers that the board check keeps off the board
    has_heading: ClassVar[bool]  # its turn about the approach axis matters (fingers close along one axis; a cup is round)

    @abstractmethod
    def held_below_top_m(self, config: MotionConfig, edge_m: float) -> float:
        """Where the tool point holds a block of edge edge_m, below its top face."""

    @abstractmethod
    def lowest_pitch_rad(self, config: MotionConfig) -> float:
        """The shallowest approach pitch a plan may fall back to."""

    @abstractmethod
    def lowest_grasp_m(self, config: MotionConfig) -> float:
        """The lowest the tool point may grasp, above the board (the pads' reach for fingers)."""

    @abstractmethod
    def body_box(self, config: MotionConfig, arm_config) -> FingerBox:
        """The box the tool occupies beyond the wrist, for the board and self-collision checks."""

    def __repr__(self) -> str:
        return f"<end effector {self.name}>"


class Fingers(EndEffector):
    name = "fingers"
    holds_by_sides = True
    release_before_pick = "open before pick"
    missed_grasp = "the fingers closed on nothing"
    has_palm = True
    has_heading = True

    def held_below_top_m(self, config: MotionConfig, edge_m: float) -> float:
        return config.grasp_depth_for(edge_m)

    def lowest_pitch_rad(self, config: MotionConfig) -> float:
        return 0.0  # horizontal

    def lowest_grasp_m(self, config: MotionConfig) -> float:
        return config.pad_reach_m  # the pads stay on the board

    def body_box(self, config: MotionConfig, arm_config) -> FingerBox:
        gripper = getattr(arm_config, "gripper", None)
        return FingerBox(config.finger_back_m, config.pad_reach_m,
                         (gripper.finger_offset_max_m if gripper is not None else 0.0) + config.finger_thickness_m,
                         config.finger_half_height_m)


class SuctionCup(EndEffector):
    name = "suction"
    holds_by_sides = False  # the seal holds the top face, which would turn sideways
    release_before_pick = "vacuum off before pick"
    missed_grasp = "the suction cup did not seal"
    has_palm = False
    has_heading = False

    def held_below_top_m(self, config: MotionConfig, edge_m: float) -> float:
        return config.suction_press_m  # pressed into the seal on the top face

    def lowest_pitch_rad(self, config: MotionConfig) -> float:
        return config.top_down_pitch_rad  # the seal holds only flat on a face

    def lowest_grasp_m(self, config: MotionConfig) -> float:
        return 0.0

    def body_box(self, config: MotionConfig, arm_config) -> FingerBox:
        cup = getattr(arm_config, "suction_cup", None)
        if cup is None:  # an arm config without the cup's size: as fingers would be (the larger box)
            return FINGERS.body_box(config, arm_config)
        return FingerBox(cup.body_length_m, 0.0, cup.body_radius_m, cup.body_radius_m)  # the cup's body, back from its lip


FINGERS = Fingers()
SUCTION = SuctionCup()
END_EFFECTORS = {tool.name: tool for tool in (FINGERS, SUCTION)}


def end_effector(kind: str | EndEffector) -> EndEffector:
    """The end effector of a workcell's gripper.type ('fingers', 'suction'), or kind itself; InvalidInput otherwise."""
    if isinstance(kind, EndEffector):
        return kind
    tool = END_EFFECTORS.get(kind) if isinstance(kind, str) else None
    if tool is None:
        raise InvalidInput(f"gripper type must be one of {', '.join(END_EFFECTORS)}, got {kind!r}")
    return tool


__all__ = ["END_EFFECTORS", "FINGERS", "SUCTION", "EndEffector", "Fingers", "SuctionCup", "end_effector"]
