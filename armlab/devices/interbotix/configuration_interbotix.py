"""Configs for the Interbotix X-Series arm and gripper (ROS 2 + interbotix_xs_modules)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from armlab.config import StrictModel


class InterbotixConnectionConfig(StrictModel):
    """How to reach the xs_sdk node: the robot model, its namespace and the node name to create."""

    robot_model: str = "rx200"
    robot_name: str | None = None          # ROS namespace; None = robot_model
    group_name: str = "arm"
    gripper_name: str = "gripper"
    node_name: str = "armlab_station"


class InterbotixArmConfig(StrictModel):
    """The arm: joint order must match the xs_sdk 'arm' group (waist … wrist_rotate for the rx200).

    stream_rate_hz: how often trajectory samples are sent. profile_time_s: the motors' time-based
    profile for each streamed goal (short = tight tracking, long = smoother, more lag).
    """

    type: Literal["interbotix"] = "interbotix"
    connection: InterbotixConnectionConfig = InterbotixConnectionConfig()
    arm_config: str = "rx200"              # config/arms/<name>.yaml: joint names and limits
    stream_rate_hz: float = Field(100.0, ge=10.0, le=500.0)
    profile_time_s: float = Field(0.1, gt=0.0, le=2.0)
    profile_accel_time_s: float = Field(0.0, ge=0.0, le=1.0)

    @model_validator(mode="after")
    def _check(self) -> InterbotixArmConfig:
        if self.profile_accel_time_s > self.profile_time_s / 2:
            raise ValueError("profile_accel_time_s must be at most half of profile_time_s")
        return self


class InterbotixGripperConfig(StrictModel):
    """The gripper: pressure 0…1 maps to the PWM range Interbotix uses; finger geometry from the arm config."""

    type: Literal["interbotix"] = "interbotix"
    connection: InterbotixConnectionConfig = InterbotixConnectionConfig()
    arm_config: str = "rx200"
    pressure: float = Field(0.5, ge=0.0, le=1.0)
    motion_time_s: float = Field(1.0, gt=0.0, le=2.0)   # how long grasp()/release() wait with wait=True
    holding_margin_m: float = Field(0.003, ge=0.0, le=0.02)  # stopped this far from fully closed = holding
