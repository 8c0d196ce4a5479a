"""The validated schema of an arm file in config/arms/ (geometry, limits, poses, gripper, base pose).

Validation happens once at load so that a bad file (NaN, zero or inverted limits, a table with the
wrong shape, a non-rigid transform, a DH table that disagrees with the PoX model) stops start-up with
a ConfigError naming the file and the field, instead of moving the arm somewhere unexpected.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from armlab.config import StrictModel

FloatRow = list[float]


def _check_rigid(matrix: list[list[float]], field: str) -> list[list[float]]:
    """Raise ValueError unless `matrix` is a 4x4 homogeneous rigid transform."""
    if len(matrix) != 4 or any(len(row) != 4 for row in matrix):
        raise ValueError(f"{field}: expected a 4x4 matrix, got {len(matrix)} rows of lengths {[len(r) for r in matrix]}")
    array = np.asarray(matrix, dtype=float)
    if not np.allclose(array[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"{field}: the last row must be [0, 0, 0, 1], got {array[3].tolist()}")
    rotation = array[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0.0:
        raise ValueError(f"{field}: the upper-left 3x3 block is not a rotation matrix")
    return matrix


class PoxConfig(StrictModel):
    """Product of exponentials in the arm's base frame: home pose M and one screw axis (w | v) per joint."""

    M: list[FloatRow]
    screw_axes: list[FloatRow]

    @field_validator("M")
    @classmethod
    def _m_is_rigid(cls, value: list[list[float]]) -> list[list[float]]:
        return _check_rigid(value, "pox.M")

    @field_validator("screw_axes")
    @classmethod
    def _axes_are_revolute(cls, value: list[list[float]]) -> list[list[float]]:
        for index, axis in enumerate(value):
            if len(axis) != 6:
                raise ValueError(f"pox.screw_axes[{index}]: expected 6 numbers (w | v), got {len(axis)}")
            if abs(math.hypot(*axis[:3]) - 1.0) > 1e-6:
                raise ValueError(f"pox.screw_axes[{index}]: w must be a unit vector (revolute joint), got {axis[:3]}")
            if abs(float(np.dot(axis[:3], axis[3:]))) > 1e-6:
                raise ValueError(f"pox.screw_axes[{index}]: v must be perpendicular to w (zero pitch)")
        return value


class DhConfig(StrictModel):
    """Standard DH table: rows of [theta_offset_rad, d_m, a_m, alpha_rad, joint_sign], then a tool transform."""

    frame: Literal["base"] = "base"
    rows: list[FloatRow]
    tool: list[FloatRow] = Field(default_factory=lambda: np.eye(4).tolist())

    @field_validator("rows")
    @classmethod
    def _rows_have_five_columns(cls, value: list[list[float]]) -> list[list[float]]:
        for index, row in enumerate(value):
            if len(row) != 5:
                raise ValueError(
                    f"dh.rows[{index}]: expected 5 numbers [theta_offset_rad, d_m, a_m, alpha_rad, joint_sign], got {len(row)}"
                )
            if row[4] not in (1.0, -1.0):
                raise ValueError(f"dh.rows[{index}]: joint_sign must be 1 or -1, got {row[4]}")
        return value

    @field_validator("tool")
    @classmethod
    def _tool_is_rigid(cls, value: list[list[float]]) -> list[list[float]]:
        return _check_rigid(value, "dh.tool")


class LimitsConfig(StrictModel):
    """Joint position limits (degrees in the file), velocity and acceleration limits (SI)."""

    lower_deg: FloatRow
    upper_deg: FloatRow
    velocity_rad_s: FloatRow
    acceleration_rad_s2: FloatRow

    @model_validator(mode="after")
    def _limits_are_sane(self) -> LimitsConfig:
        for index, (low, high) in enumerate(zip(self.lower_deg, self.upper_deg)):
            if not low < high:
                raise ValueError(f"limits.lower_deg[{index}] = {low} must be below limits.upper_deg[{index}] = {high}")
        for field in ("velocity_rad_s", "acceleration_rad_s2"):
            for index, value in enumerate(getattr(self, field)):
                if not value > 0.0:
                    raise ValueError(f"limits.{field}[{index}] must be positive, got {value}")
        return self


class PosesConfig(StrictModel):
    """Named joint poses (radians)."""

    home_rad: FloatRow
    sleep_rad: FloatRow


class GripperConfig(StrictModel):
    """Parallel gripper: each finger's distance from the centre line, pad thickness, grasp force."""

    finger_offset_min_m: float = Field(ge=0.0)
    finger_offset_max_m: float = Field(gt=0.0)
    pad_thickness_m: float = Field(ge=0.0)
    grasp_effort_n: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _range_is_sane(self) -> GripperConfig:
        if not self.finger_offset_min_m < self.finger_offset_max_m:
            raise ValueError("gripper.finger_offset_min_m must be below gripper.finger_offset_max_m")
        if self.pad_thickness_m >= self.finger_offset_max_m:
            raise ValueError("gripper.pad_thickness_m must be smaller than gripper.finger_offset_max_m")
        return self


class SuctionCupConfig(StrictModel):
    """A vacuum suction cup at the tool point: the lip (a ring of radius lip_radius_m around the approach
    axis, at the tool point) and the cup body behind it (body_radius_m, body_length_m back toward the
    flange). The tool point itself (the lip centre) is dh.tool."""

    lip_radius_m: float = Field(gt=0.0, le=0.1)
    body_radius_m: float = Field(gt=0.0, le=0.1)
    body_length_m: float = Field(gt=0.0, le=0.3)


class ArmConfig(StrictModel):
    """One arm file. `family: rx200` enables the closed-form IK; `generic` uses the numerical IK only."""

    name: str = Field(min_length=1)
    family: Literal["rx200", "generic"] = "generic"
    vendor: str | None = None  # who makes it ("interbotix", "universal_robots"): the Interbotix client facade needs "interbotix"
    joint_names: list[str] = Field(min_length=1)
    pox: PoxConfig | None = None
    dh: DhConfig | None = None
    urdf_origins: dict[str, list[float]] | None = None
    limits: LimitsConfig
    poses: PosesConfig
    gripper: GripperConfig | None = None
    suction_cup: SuctionCupConfig | None = None
    T_world_base: list[FloatRow] = Field(default_factory=lambda: np.eye(4).tolist())
    payload_kg: float | None = Field(default=None, gt=0.0)
    reach_m: float | None = Field(default=None, gt=0.0)
    accuracy_m: float | None = Field(default=None, gt=0.0)
    # Nominal mass of each joint's link (kg, the link joint i moves, its centre halfway to the next joint origin):
    # the gravity torques of the arm calibration's compliance (armlab.kinematics.arm_calibration). None: equal masses.
    link_masses_kg: list[Annotated[float, Field(ge=0.0)]] | None = None
    # Radius (m) of the link each joint moves, a capsule from its joint origin to the next one's (the last joint's
    # to the gripper point): the trajectory check keeps every link that far above the board, and the simulation
    # builds its links with it. None: links as lines. The fingers and the suction cup have their own boxes.
    link_radii_m: list[Annotated[float, Field(ge=0.0, le=0.2)]] | None = None

    @field_validator("T_world_base")
    @classmethod
    def _base_is_rigid(cls, value: list[list[float]]) -> list[list[float]]:
        return _check_rigid(value, "T_world_base")

    @model_validator(mode="after")
    def _shapes_agree(self) -> ArmConfig:
        dof = len(self.joint_names)
        if len(set(self.joint_names)) != dof:
            raise ValueError(f"joint_names: names must be unique, got {self.joint_names}")
        if self.pox is None and self.dh is None:
            raise ValueError("pox, dh: at least one kinematic description is required")
        if self.pox is not None and len(self.pox.screw_axes) != dof:
            raise ValueError(f"pox.screw_axes: expected {dof} rows (one per joint), got {len(self.pox.screw_axes)}")
        if self.dh is not None and len(self.dh.rows) != dof:
            raise ValueError(f"dh.rows: expected {dof} rows (one per joint), got {len(self.dh.rows)}")
        for field in ("lower_deg", "upper_deg", "velocity_rad_s", "acceleration_rad_s2"):
            values = getattr(self.limits, field)
            if len(values) != dof:
                raise ValueError(f"limits.{field}: expected {dof} values (one per joint), got {len(values)}")
        if self.link_masses_kg is not None and len(self.link_masses_kg) != dof:
            raise ValueError(f"link_masses_kg: expected {dof} values (one per joint), got {len(self.link_masses_kg)}")
        if self.link_radii_m is not None and len(self.link_radii_m) != dof:
            raise ValueError(f"link_radii_m: expected {dof} values (one per joint), got {len(self.link_radii_m)}")
        lower = np.radians(self.limits.lower_deg)
        upper = np.radians(self.limits.upper_deg)
        for field in ("home_rad", "sleep_rad"):
            pose = np.asarray(getattr(self.poses, field))
            if pose.shape != (dof,):
                raise ValueError(f"poses.{field}: expected {dof} values (one per joint), got {pose.size}")
            if np.any(pose < lower - 1e-9) or np.any(pose > upper + 1e-9):
                raise ValueError(f"poses.{field}: {pose.tolist()} is outside the joint limits")
        if self.urdf_origins is not None:
            expected = [*self.joint_names, "gripper_point"]
            if list(self.urdf_origins) != expected:
                raise ValueError(f"urdf_origins: expected the keys {expected} in order, got {list(self.urdf_origins)}")
            for key, origin in self.urdf_origins.items():
                if len(origin) != 3:
                    raise ValueError(f"urdf_origins.{key}: expected [x, y, z], got {len(origin)} numbers")
            if self.pox is None:
                raise ValueError("urdf_origins: needs pox (the joint axes come from its screw axes)")
        if self.suction_cup is not None and self.dh is not None:
            reach = float(np.linalg.norm(np.asarray(self.dh.tool, dtype=float)[:3, 3]))
            if self.suction_cup.body_length_m > reach + 1e-9:
                raise ValueError(
                    f"suction_cup.body_length_m: {self.suction_cup.body_length_m} m is longer than the flange-to-tool-point "
                    f"distance of dh.tool ({reach:.4f} m): the cup would reach behind the flange"
                )
        if self.family == "rx200" and (self.pox is None or dof != 5):
            raise ValueError("family: 'rx200' needs a pox description and 5 joints")
        return self
