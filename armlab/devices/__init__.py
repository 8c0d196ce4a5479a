"""Device interfaces (Arm, Gripper, Camera). Backends live in subpackages and are imported lazily by
the factories in `armlab.devices.factory`, so importing this package never pulls in a vendor SDK."""

from armlab.devices.arm import Arm, JointState, JointTrajectory
from armlab.devices.camera import Camera, Frame, Intrinsics
from armlab.devices.gripper import Gripper, GripperState

__all__ = [
    "Arm",
    "Camera",
    "Frame",
    "Gripper",
    "GripperState",
    "Intrinsics",
    "JointState",
    "JointTrajectory",
]
