"""InterbotixGripper: the Gripper interface on an Interbotix gripper in PWM/current mode (ROS 2).

Thin by design: closing/opening publish a signed effort through gripper_controller (negative closes,
as the xs_sdk's own limit guard assumes); the span between the pads comes from the left finger's
joint state (its offset from the centre line) minus the pads configured in the arm file.
"""

from __future__ import annotations

import time

from armlab.config import read_config_file, resolve_config_path
from armlab.devices.gripper import Gripper, GripperState
from armlab.devices.interbotix.configuration_interbotix import InterbotixGripperConfig
from armlab.devices.interbotix.connection import InterbotixConnection
from armlab.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError


class InterbotixGripper(Gripper):
    """An Interbotix parallel gripper; pass the arm's `connection` to share one ROS node."""

    def __init__(self, config: InterbotixGripperConfig, connection: InterbotixConnection | None = None) -> None:
        self.config = config
        self.connection = connection or InterbotixConnection(config.connection)
        gripper = read_config_file(resolve_config_path(config.arm_config, "arms"))["gripper"]
        self._pad_m = float(gripper["pad_thickness_m"])
        self._finger_min_m = float(gripper["finger_offset_min_m"])
        self._bot = None
        self._command = "release"

    def __str__(self) -> str:
        return f"InterbotixGripper({self.config.connection.robot_name or self.config.connection.robot_model})"

    @property
    def is_connected(self) -> bool:
        return self._bot is not None

    def connect(self) -> None:
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self}: already connected; call close() before connecting again")
        try:
            bot = self.connection.open()
        except (ImportError, ConnectionError) as error:  # say which device could not connect
            raise type(error)(f"{self}: {error}") from error
        try:
            if getattr(bot, "gripper", None) is None:
                raise ConnectionError(f"{self}: the robot has no gripper named '{self.config.connection.gripper_name}'")
            bot.gripper.set_pressure(self.config.pressure)
            self._bot = bot
        except BaseException:
            self.connection.release()
            raise

    def close(self) -> None:
        if self._bot is None:
            return
        self._bot = None
        self.connection.release()

    def _require_connected(self):
        if self._bot is None:
            raise DeviceNotConnectedError(f"{self}: not connected: call connect() first")
        return self._bot

    def grasp(self, wait: bool = True) -> None:
        bot = self._require_connected()
        self._command = "grasp"
        bot.gripper.gripper_controller(-bot.gripper.gripper_value, self.config.motion_time_s if wait else 0.0)

    def release(self, wait: bool = True) -> None:
        bot = self._require_connected()
        self._command = "release"
        bot.gripper.gripper_controller(bot.gripper.gripper_value, self.config.motion_time_s if wait else 0.0)

    def read_state(self) -> GripperState:
        bot = self._require_connected()
        with bot.core.js_mutex:
            finger_m = float(bot.core.joint_states.position[bot.gripper.left_finger_index])
        width_m = max(0.0, 2.0 * finger_m - 2.0 * self._pad_m)
        holding = self._command == "grasp" and finger_m > self._finger_min_m + self.config.holding_margin_m
        return GripperState(width_m=width_m, command=self._command, holding=holding, timestamp_s=time.time())

    def stop(self) -> None:
        """Zero the finger PWM (halts them), unless they are closed on something: then the grasp PWM keeps
        squeezing it (zero PWM would let a held block fall)."""
        bot = self._require_connected()
        if self.read_state().holding:
            return
        bot.gripper.gripper_controller(0.0, 0.0)
