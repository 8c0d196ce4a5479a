"""The arm's and gripper's part of the station's status (GET /api/status): joints, gripper, the gripper's pose and
whether the arm moves, read from the devices; with a device lost its last reading is shown.

Owned by core.Station (station.readings); the gate adds its own state, lease, job and calibration to it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armlab.station.perception import DEVICE_ERRORS
from armlab.station.telemetry import gripper_pose_from_matrix


def arm_turning(arm: Any, joint_state: Any, moving_speed_rad_s: float) -> bool:
    """What counts as the arm moving, read from the devices: the arm says it is moving (a trajectory running), or a
    joint in `joint_state` (a JointState just read) turns faster than moving_speed_rad_s (pushed, falling limp)."""
    speed = np.abs(np.asarray(joint_state.velocity_rad_s, dtype=float))
    return bool(arm.is_moving()) or bool(speed.size and speed.max() > moving_speed_rad_s)


class ArmReadings:
    """Reads the arm and gripper for the status; keeps the last joints read (shown while the arm cannot be read).

    model: the ArmModel (None: a station with no arm); moving_speed_rad_s: a joint faster than this is moving."""

    def __init__(self, arm: Any, gripper: Any, model: Any, moving_speed_rad_s: float) -> None:
        self._arm, self._gripper, self._model, self._moving_speed_rad_s = arm, gripper, model, moving_speed_rad_s
        self._last_joints: np.ndarray | None = None

    def read(self) -> dict:
        """The status' joints_rad, joint_names, joint_limits_rad, gripper, gripper_pose and moving."""
        model, has_arm = self._model, self._model is not None
        moving, gripper_dict = False, {"width_m": 0.0, "holding": False, "command": "release"}
        try:
            joint_state = self._arm.read_joint_state()
            q = np.asarray(joint_state.position_rad, dtype=float)
            self._last_joints = q
            moving = arm_turning(self._arm, joint_state, self._moving_speed_rad_s)
        except DEVICE_ERRORS:
            q = self._last_joints if self._last_joints is not None else np.asarray(model.home_rad if has_arm else [], dtype=float)
        try:
            gripper = self._gripper.read_state()
            gripper_dict = {"width_m": float(gripper.width_m), "holding": bool(gripper.holding), "command": gripper.command}
        except DEVICE_ERRORS:
            pass
        return {
            "joints_rad": [float(v) for v in q],
            "joint_names": list(model.joint_names) if has_arm else [],
            "joint_limits_rad": [[float(lo), float(hi)] for lo, hi in zip(model.lower_rad, model.upper_rad)] if has_arm else [],
            "gripper": gripper_dict,
            "gripper_pose": gripper_pose_from_matrix(self._gripper_pose(q), np.asarray(model.T_world_base)[:3, 3]) if has_arm else None,
            "moving": moving,
        }

    def _gripper_pose(self, q_read: np.ndarray) -> np.ndarray:
        """The gripper's pose from joint readings: the calibrated arm's (fk_measured) when there is one."""
        fk_measured = getattr(self._model, "fk_measured", None)
        return fk_measured(q_read) if fk_measured is not None else self._model.fk(q_read)
