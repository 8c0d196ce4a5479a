"""Arm kinematics: arm models from config/arms/, DH and product-of-exponentials FK, closed-form IK
for the RX200 family and numerical IK for any arm.

    from armlab.kinematics import load_arm, Unreachable
    arm = load_arm("rx200")
    T_world_gripper = arm.fk(q)                          # (4, 4), or (N, 4, 4) for q of shape (N, 5)
    q = arm.ik([0.1, 0.25, 0.02], pitch=None, yaw=0.3)   # raises Unreachable (a ValueError) with the reason

Modules: screws (Modern Robotics maths), dh (DH tables), rx200_geometry, ik_rx200 and ik_rx200_batch (closed form),
ik_numeric (Levenberg-Marquardt), arm_config (the validated file schema), arm_model (ArmModel, load_arm).
"""

from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.arm_model import ArmModel, load_arm
from armlab.kinematics.errors import Unreachable

__all__ = ["ArmConfig", "ArmModel", "Unreachable", "load_arm"]
