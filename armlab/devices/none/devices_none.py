"""NoArm and NoGripper: what a station without an arm runs on (perception only).

They read as an arm with no joints (empty joint state, never moving) and an open, empty gripper, so the
station's status, device watch, e-stop and camera frames work unchanged; every command that would move
something raises NoArmError. The station refuses those commands itself before they get here (Station with
model None); these refusals are the second line.
"""

from __future__ import annotations

import time
from typing import Literal

import numpy as np

from armlab.config import StrictModel
from armlab.devices.arm import Arm, JointState, JointTrajectory
from armlab.devices.gripper import Gripper, GripperState
from armlab.errors import NoArmError


class NoArmConfig(StrictModel):
    """`type: none` (config/devices/none.yaml): the station has no arm."""

    type: Literal["none"] = "none"


class NoGripperConfig(StrictModel):
    """`type: none`: the station has no gripper."""

    type: Literal["none"] = "none"


class NoArm(Arm):
    """An arm with no joints: reads answer, commands raise NoArmError."""

    joint_names: tuple[str, ...] = ()

    def __init__(self, config: NoArmConfig | None = None) -> None:
        self.config = config or NoArmConfig()
        self._connected = False

    def __str__(self) -> str:
        return "NoArm"

    def connect(self) -> None:
        self._connected = True

    def close(self) -> None:
        self._connected = False

    @property
    def is_connected(self) -> bool:
        return self._connected

    def read_joint_state(self) -> JointState:
        return JointState(position_rad=np.zeros(0), velocity_rad_s=np.zeros(0), timestamp_s=time.time())

    def command_trajectory(self, trajectory: JointTrajectory, wait: bool = False, start_time_s: float | None = None) -> float:
        raise NoArmError("move")

    def is_moving(self) -> bool:
        return False

    def stop(self) -> None:
        """Nothing moves: halting is always done."""

    def set_torque(self, enabled: bool) -> None:
        raise NoArmError("torque")


class NoGripper(Gripper):
    """A gripper that is not there: open and empty; grasp and release raise NoArmError."""

    def __init__(self, config: NoGripperConfig | None = None) -> None:
        self.config = config or NoGripperConfig()
        self._connected = False

    def __str__(self) -> str:
        return "NoGripper"

    def connect(self) -> None:
        self._connected = True

    def close(self) -> None:
        self._connected = False

    @property
    def is_connected(self) -> bool:
        return self._connected

    def grasp(self, wait: bool = True) -> None:
        raise NoArmError("gripper")

    def release(self, wait: bool = True) -> None:
        raise NoArmError("gripper")

    def read_state(self) -> GripperState:
        return GripperState(width_m=0.0, command="release", holding=False, timestamp_s=time.time())

    def stop(self) -> None:
        """Nothing to hold."""
