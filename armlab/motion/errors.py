"""The motion planners' refusals, below the planners that raise them (cartesian, pose_path, pose_step,
gripper_step) so none needs another's module for its errors."""

from __future__ import annotations

from armlab.kinematics.errors import Unreachable


class DiscontinuousPath(ValueError):
    """IK switched branch along a Cartesian segment (the joints would jump); the message names the joint."""


class StepRefused(Unreachable):
    """A jog step that cannot keep the gripper's orientation or line within the tolerances (HTTP 422)."""
