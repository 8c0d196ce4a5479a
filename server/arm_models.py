"""Request bodies of the arm's routes (server/routes/arm.py): joint and pose moves, torque, joint and Cartesian jogs, steps,
gripper."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from server.response_models import GripperPose
from server.wire_base import Angle, MovingTime, Position, Request, SpeedPercent, Velocity, Wire


class JointsRequest(Request):
    q_rad: list[Angle] = Field(min_length=1, max_length=12, description="joint positions, radians, in joint_names order")
    moving_time_s: MovingTime | None = Field(None, description="move duration; None = as fast as the limits allow")


class PoseRequest(Request):
    position_m: Position = Field(description="gripper point in the world (board) frame")
    pitch_rad: Angle | None = Field(None, description="approach angle below horizontal; +π/2 = straight down; None = steepest")
    yaw_rad: Angle | None = Field(None, description="block yaw in the world frame the fingers align with")
    moving_time_s: MovingTime | None = None


class MoveCheck(Wire):
    """What a joint or pose move would do, checked like the move itself; nothing moved (POST /api/arm/pose/check, /api/arm/joints/check)."""

    q_rad: list[float] = Field(description="the goal joints, radians, joint_names order")
    duration_s: float = Field(description="the planned move's duration from where the arm is now")
    gripper_pose: GripperPose = Field(description="the gripper at the goal (commanded kinematics)")


class PoseNameRequest(Request):
    """Optional body of /api/arm/home and /api/arm/sleep."""

    moving_time_s: MovingTime | None = None


class TorqueRequest(Request):
    enabled: bool
    confirm: bool = Field(False, description="torque off outside teach lets the arm fall: needs confirm: true")


class JogRequest(Request):
    """Hold-to-run jog: joint velocities kept for jog_hold_s after each heartbeat (this request, or a
    heartbeat), then the arm ramps to rest by itself."""

    velocity_rad_s: list[Velocity] = Field(min_length=1, max_length=12, description="joint velocities, joint_names order; zeros stop")
    speed_percent: SpeedPercent = 100.0


JOG_SPEED_LIMIT_M_S = 0.5  # the schema's bound; the station applies its jog_max_speed_m_s (config/motion.yaml)


class CartesianJogRequest(Request):
    """Hold-to-run Cartesian jog: the gripper point moves along world x|y|z at velocity_m_s (signed; its top speed is
    the station's jog_max_speed_m_s, scaled by speed_percent) keeping its pitch and yaw, for jog_hold_s after each
    heartbeat, then brakes to rest by itself; where the line cannot go on it stops before it (422 when it cannot move)."""

    axis: Literal["x", "y", "z"] = Field(description="the world axis the gripper point moves along")
    velocity_m_s: float = Field(ge=-JOG_SPEED_LIMIT_M_S, le=JOG_SPEED_LIMIT_M_S,
                                description="metres per second along the axis (+ or −); 0 ramps down to rest")
    speed_percent: SpeedPercent = 100.0


STEP_DISTANCE_LIMIT_M = 0.1
STEP_ANGLE_LIMIT_RAD = math.pi / 4


class StepRequest(Request):
    """A jog step of the gripper: distance_m along world x|y|z keeping its pitch and yaw (within 0.5°,
    the point within 1 mm of the line), or angle_rad of pitch (about the gripper point) or wrist roll."""

    axis: Literal["x", "y", "z", "pitch", "roll"]
    distance_m: float | None = Field(
        None, ge=-STEP_DISTANCE_LIMIT_M, le=STEP_DISTANCE_LIMIT_M, description="metres along the world axis (x, y, z); non-zero"
    )
    angle_rad: float | None = Field(
        None, ge=-STEP_ANGLE_LIMIT_RAD, le=STEP_ANGLE_LIMIT_RAD, description="radians of pitch (+ = down) or roll; non-zero"
    )
    speed_percent: SpeedPercent = 100.0

    @model_validator(mode="after")
    def _one_amount(self) -> StepRequest:
        linear = self.axis in ("x", "y", "z")
        amount, other = (self.distance_m, self.angle_rad) if linear else (self.angle_rad, self.distance_m)
        needed = "distance_m" if linear else "angle_rad"
        if other is not None or amount is None:
            raise ValueError(f"a {self.axis} step needs {needed} alone")
        if amount == 0.0:
            raise ValueError(f"{needed} must not be zero")
        return self


class GripperRequest(Request):
    action: Literal["grasp", "release"]
