"""The rig of a workcell: the gripper on the arm (and its tag), the arm's base pose and the camera mount."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from armlab.config import StrictModel
from armlab.workcell.fields import Length

GRIPPER_TYPES = ("fingers", "suction")


class GripperMarkerSpec(StrictModel):
    """A tag of the board's family fixed flat on the gripper, for finding the gripper in the camera
    (armlab.vision.gripper_marker): its id (not a board tag's), the detected square's edge, and its
    centre in the gripper-point frame (x along the approach, y along the fingers, z up when the
    gripper is level), as measured on the arm."""

    id: Annotated[int, Field(ge=0)]
    size_m: Length
    position_m: tuple[float, float, float]


class GripperChoice(StrictModel):
    """The end effector on the arm: `fingers` (a parallel gripper: the arm file's `gripper:` width range)
    or `suction` (a vacuum cup: the arm file's `suction_cup:`); marker: the tag on it, if any."""

    type: Literal["fingers", "suction"] = "fingers"
    marker: GripperMarkerSpec | None = None


class ArmBaseSpec(StrictModel):
    """The arm's base frame on the board: origin position_m (world), rotated yaw_deg about world z."""

    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: Annotated[float, Field(ge=-180.0, le=180.0)] = 0.0

    @property
    def T_world_base(self) -> np.ndarray:
        yaw = np.radians(self.yaw_deg)
        T = np.eye(4)
        T[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
        T[:3, 3] = self.position_m
        return T


class CameraMountSpec(StrictModel):
    """Nominal overhead camera mount (what software may assume before calibrating): camera centre in the
    world frame and tilt about the camera x axis toward -y. Overrides the camera file's `mount`."""

    position_m: tuple[float, float, float]
    tilt_deg: Annotated[float, Field(ge=0.0, le=45.0)]


class CameraSpec(StrictModel):
    """The overhead RGB-D camera: config/cameras/<name>.yaml, and this workcell's mount (None = the file's)."""

    name: str = "sim_l515"
    mount: CameraMountSpec | None = None
