"""Interbotix X-Series backend (ROS 2 + interbotix_xs_modules, imported only when connecting)."""

from armlab.devices.interbotix.arm_interbotix import InterbotixArm
from armlab.devices.interbotix.configuration_interbotix import (
    InterbotixArmConfig,
    InterbotixConnectionConfig,
    InterbotixGripperConfig,
)
from armlab.devices.interbotix.connection import InterbotixConnection, InterbotixNotInstalledError
from armlab.devices.interbotix.gripper_interbotix import InterbotixGripper

__all__ = [
    "InterbotixArm",
    "InterbotixArmConfig",
    "InterbotixConnection",
    "InterbotixConnectionConfig",
    "InterbotixGripper",
    "InterbotixGripperConfig",
    "InterbotixNotInstalledError",
]
