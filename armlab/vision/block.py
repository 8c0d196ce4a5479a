"""The detected block as perception reports it (world metres, frame time and arm pose it was seen at)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class Block:
    """A detected block (the top one of a stack); positions in world metres, yaw mod pi/2 in [-pi/4, pi/4).

    Equal only to itself (eq=False): two detections are two blocks, and a field-wise == would compare numpy arrays."""

    color: str
    size: str
    position_m: np.ndarray
    yaw_rad: float
    height_m: float
    stack_level: int
    center_px: np.ndarray
    contour_px: np.ndarray
    is_cube: bool = True
    occluded: bool = False
    aruco_id: int | None = None
    destination: int | None = None
    side_m: float = 0.0
    stack_sizes: tuple[str, ...] = field(default=())
    seen_time_s: float | None = None  # capture time (time.time()) of the frame it was seen in
    seen_arm_joints_rad: tuple[float, ...] | None = None  # the measured arm joints at that frame
    color_lab: tuple[float, float, float] | None = None  # the top face's board-normalised CIELAB (armlab.vision.colors)

    def to_dict(self) -> dict:
        return {
            "color": self.color,
            "size": self.size,
            "position_m": [float(x) for x in self.position_m],
            "yaw_rad": float(self.yaw_rad),
            "height_m": float(self.height_m),
            "stack_level": int(self.stack_level),
            "stack_sizes": list(self.stack_sizes),
            "center_px": [float(x) for x in self.center_px],
            "is_cube": bool(self.is_cube),
            "occluded": bool(self.occluded),
            "aruco_id": self.aruco_id,
            "destination": self.destination,
            "side_m": float(self.side_m),
            "seen_time_s": self.seen_time_s,
            "seen_arm_joints_rad": None if self.seen_arm_joints_rad is None else list(self.seen_arm_joints_rad),
            "color_lab": None if self.color_lab is None else [float(x) for x in self.color_lab],
        }
