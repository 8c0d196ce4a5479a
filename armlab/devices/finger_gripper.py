"""The finger gripper's shape: its dimensions (config/sim.yaml `gripper:`, the sizes the simulation builds
its fingers from) and the outline of its palm and fingers around the finger plane that the arm's body gives
planners (armlab.devices.arm_body.load_finger_gripper_outline; armlab.skills.side_grasp). Below the simulator,
which builds the same gripper from the same body, so a planner needs no simulator to know the gripper's shape."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated

from pydantic import Field

from armlab.config import StrictModel, read_config_file, resolve_config_path, validate_config
from armlab.errors import ConfigError

Positive = Annotated[float, Field(gt=0.0)]
NonNegative = Annotated[float, Field(ge=0.0)]


class FingerGripperConfig(StrictModel):
    """config/sim.yaml `gripper:`: the finger servo and pads the simulation builds, and the palm and finger
    sizes the outline below is made of."""

    kp_n_m: Positive
    damping_n_s_m: NonNegative
    armature_kg: NonNegative
    finger_mass_kg: Positive
    pad_width_m: Positive
    pad_length_m: Positive
    tip_beyond_gripper_point_m: float
    palm_depth_m: Positive
    palm_half_height_m: Positive
    palm_side_margin_m: NonNegative
    finger_link_margin_m: NonNegative
    pad_friction: list[NonNegative] = Field(min_length=3, max_length=3)
    pad_solref: list[float] = Field(min_length=2, max_length=2)
    pad_solimp: list[float] = Field(min_length=3, max_length=5)
    stop_speed_m_s: Positive
    stop_time_s: Positive
    open_preload_m: NonNegative = 0.001  # open: the fingers are driven this far beyond their stop (sim.yaml says why)


@dataclass(frozen=True)
class FingerGripperOutline:
    """The finger gripper's parts around the finger plane, relative to the gripper point (x = approach axis),
    as the simulation builds them: for planners that keep the palm and open fingers clear of things."""

    palm_half_height_m: float  # palm extent either side of the finger plane
    palm_front_behind_m: float  # the palm's front face, this far behind the gripper point
    palm_back_behind_m: float  # the palm's back face (the wrist_rotate joint), this far behind it
    finger_half_height_m: float  # finger link extent either side of the finger plane
    finger_tip_beyond_m: float  # the finger tips, this far beyond the gripper point
    open_outer_m: float  # the palm's and the open fingers' outer faces from the finger plane's centre


def load_finger_gripper_config(name: str = "sim") -> FingerGripperConfig:
    """The `gripper:` section of config/<name>.yaml; ConfigError naming the file and field."""
    path = resolve_config_path(name, ".")
    section = read_config_file(path).get("gripper")
    if not isinstance(section, dict):
        raise ConfigError(f"{path}: no gripper section")
    return validate_config(section, FingerGripperConfig, f"{path} gripper")
