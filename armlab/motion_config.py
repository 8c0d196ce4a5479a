"""MotionConfig: pick/place heights, vertical-segment speeds and safety clearance (config/motion.yaml).

A config-level module (it needs only armlab.config), below the workcell, whose `motion:` overrides it validates."""

from __future__ import annotations

import math
from pathlib import Path

from pydantic import Field, model_validator

from armlab.config import StrictModel, config_dir, load_config
from armlab.errors import InvalidInput


class MotionConfig(StrictModel):
    """Validated motion settings; all lengths in metres of the gripper point, world frame."""

    approach_height_m: float = Field(0.08, gt=0.0, le=0.3)
    lift_height_m: float = Field(0.08, gt=0.0, le=0.3)
    grasp_depth_m: float = Field(0.015, ge=0.0, le=0.05)
    pad_reach_m: float = Field(0.009, ge=0.0, le=0.1)
    place_clearance_m: float = Field(0.005, ge=0.0, le=0.05)
    board_clearance_m: float = Field(0.003, ge=0.0, le=0.05)
    vertical_speed_m_s: float = Field(0.10, gt=0.0, le=1.0)
    vertical_accel_m_s2: float = Field(0.40, gt=0.0, le=10.0)
    sample_rate_hz: float = Field(100.0, ge=100.0, le=1000.0)
    move_time_s: float | None = Field(None, gt=0.0, le=30.0)
    accel_time_s: float | None = Field(None, gt=0.0, le=15.0)
    top_down_pitch_rad: float = Field(math.pi / 2, ge=0.0, le=math.pi / 2 + 1e-9)
    # Checked by the station for every trajectory it sends (armlab.motion.safety): link points stay in
    # the box, no joint changes more than max_step_rad between two samples, and a trajectory starts
    # within start_tolerance_rad of the measured joints.
    workspace_min_m: tuple[float, float, float] = (-0.55, -0.40, 0.0)
    workspace_max_m: tuple[float, float, float] = (0.55, 0.60, 0.70)
    max_step_rad: float = Field(0.1, gt=0.0, le=1.0)
    start_tolerance_rad: float = Field(0.05, gt=0.0, le=0.5)
    jog_hold_s: float = Field(0.2, gt=0.0, le=2.0)  # a jog runs this long after its last heartbeat, then brakes
    # The fastest hold-to-run joint jog (rad/s, capped by each joint's own limit): the deadman's stopping distance
    # is v * jog_hold_s + v^2 / (2 a), 0.22 rad at 0.8 rad/s and 5 rad/s^2 (1.93 rad at pi rad/s with a 0.3 s hold).
    jog_max_speed_rad_s: float = Field(0.8, gt=0.0, le=10.0)
    # A motion that replaces a running one takes over this long after it is planned (the running trajectory goes
    # on meanwhile), so planning and checking never make the command jump (armlab.motion.handover).
    handover_lead_s: float = Field(0.05, ge=0.02, le=0.5)
    # Jog steps of the gripper (POST /api/arm/step) at 100 % speed; the operator's override scales the speeds.
    step_speed_m_s: float = Field(0.05, gt=0.0, le=0.5)
    step_accel_m_s2: float = Field(0.2, gt=0.0, le=5.0)
    step_rotation_speed_rad_s: float = Field(0.5, gt=0.0, le=3.0)
    step_rotation_accel_rad_s2: float = Field(2.0, gt=0.0, le=20.0)
    # The open fingers as a box in the gripper frame (across: the arm's finger_offset_max_m + finger_thickness_m):
    # jog steps keep its lowest corner board_clearance_m above the board.
    finger_back_m: float = Field(0.07, ge=0.0, le=0.3)  # the fingers reach this far back from the gripper point
    finger_thickness_m: float = Field(0.008, ge=0.0, le=0.05)
    finger_half_height_m: float = Field(0.012, ge=0.0, le=0.1)
    # The arm against itself (every trajectory the station sends): the gripper point, the finger tips and a held
    # block, each with self_clearance_m around it, stay out of the base (a cylinder of base_radius_m around the
    # first joint's axis up to the second joint; the RX200's base plate is 100 mm square) and 2x that from the
    # upper arm. The fingers' box (above) stays above the board itself.
    base_radius_m: float = Field(0.06, ge=0.0, le=0.5)
    self_clearance_m: float = Field(0.03, ge=0.0, le=0.2)
    # A suction cup lands on the block's top face and presses this far into its seal (the tool point below the face).
    suction_press_m: float = Field(0.002, ge=0.0, le=0.01)

    @model_validator(mode="after")
    def _workspace_box(self) -> MotionConfig:
        for axis, low, high in zip("xyz", self.workspace_min_m, self.workspace_max_m):
            if not (math.isfinite(low) and math.isfinite(high) and low < high):
                raise InvalidInput(f"workspace box: {axis} must have finite min < max, got [{low}, {high}]")
        return self

    @property
    def workspace_m(self) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """((xmin, ymin, zmin), (xmax, ymax, zmax)): the workspace box, world frame."""
        return self.workspace_min_m, self.workspace_max_m

    @model_validator(mode="after")
    def _accel_within_move(self) -> MotionConfig:
        if self.move_time_s is not None and self.accel_time_s is not None and self.accel_time_s > self.move_time_s / 2:
            raise InvalidInput(f"accel_time_s ({self.accel_time_s}) must be at most half of move_time_s ({self.move_time_s})")
        return self

    def grasp_depth_for(self, edge_m: float) -> float:
        """How far below a block's top face the gripper point closes: grasp_depth_m, but never so deep
        that the pads (reaching pad_reach_m below the gripper point) touch what the block stands on."""
        return max(0.0, min(self.grasp_depth_m, edge_m - self.pad_reach_m))


def load_motion_config(path: str | Path | None = None) -> MotionConfig:
    """Load config/motion.yaml (or `path`); ConfigError naming the file and field when invalid."""
    return load_config(Path(path) if path is not None else config_dir() / "motion.yaml", MotionConfig)
