"""No arm and no gripper: the devices of a perception-only station (`armlab serve --arm none`)."""

from armlab.devices.none.devices_none import NoArm, NoArmConfig, NoGripper, NoGripperConfig

__all__ = ["NoArm", "NoArmConfig", "NoGripper", "NoGripperConfig"]
