"""Telemetry: the station's status as plain JSON-ready dicts, published at a fixed rate.

Pure helpers turn library objects (detected blocks, tags, poses) into wire dicts; the
TelemetryPublisher thread snapshots the station at `rate_hz` into a NewestSlot. Detections is what the
station's detection accessor returns: typed blocks, serialised by its to_dict (GET /api/detections, telemetry).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armlab.kinematics.rx200_geometry import approach_pitch_rad
from armlab.station.perception import _Worker
from armlab.station.slots import NewestSlot
from armlab.vision.block import Block


def _floats(values) -> list[float]:
    return [float(value) for value in np.asarray(values, dtype=float).ravel()]


def gripper_pose_from_matrix(T_world_gripper: np.ndarray, base_xyz_m=(0.0, 0.0, 0.0)) -> dict:
    """Position, pitch and yaw of the gripper point from its world pose (x axis = approach axis).

    pitch_rad: the pitch the arm's `ik` takes (ArmModel.pitch_of): the approach axis below the horizontal
    in the vertical plane through the base axis (at base_xyz_m) and the gripper point, 0 = pointing away
    from the base axis, +π/2 = straight down, beyond ±π/2 = pointing back toward it; so a pose sent back
    with this pitch is the same pose (an asin pitch folded those onto the pointing-away ones).
    yaw_rad: the heading of the fingers' closing axis (the pose's y axis) in the board plane,
    measured from world +x, so it is meaningful when pointing straight down too.
    """
    T = np.asarray(T_world_gripper, dtype=float)
    pitch = approach_pitch_rad(T, tuple(float(v) for v in base_xyz_m))
    closing = T[:3, 1]
    yaw = math.atan2(float(closing[1]), float(closing[0]))
    return {"position_m": _floats(T[:3, 3]), "pitch_rad": pitch, "yaw_rad": yaw}


@dataclass(frozen=True)
class Detections:
    """The newest detected blocks (Station.detections) in detection order (a block's index is its wire id), each
    stamped with its frame's capture time; none, with the reason, while stale (the camera lost, perception older
    than camera_timeout_s)."""

    blocks: tuple[Block, ...]
    time_s: float  # when perception made them (time.time())
    frame_sequence: int  # the frame they were seen in (-1: no perception yet)
    stale_reason: str | None = None

    @property
    def stale(self) -> bool:
        return self.stale_reason is not None

    def to_dict(self) -> dict:
        """The wire form (server's DetectionsResponse): {data, count, time_s, frame_sequence, stale, stale_reason}."""
        data = [block_to_dict(index, block) for index, block in enumerate(self.blocks)]
        return {"data": data, "count": len(data), "time_s": self.time_s, "frame_sequence": self.frame_sequence,
                "stale": self.stale, "stale_reason": self.stale_reason}


def block_to_dict(index: int | None, block) -> dict:
    """A detected block (armlab.vision Block) as the wire dict of GET /api/detections; seen_time_s
    (the capture time of the frame it was seen in) when the block carries it."""
    size = getattr(block, "size", None)
    data = {
        "id": index,
        "color": getattr(block, "color", None),
        "size": size,
        "position_m": _floats(block.position_m),
        "yaw_rad": float(getattr(block, "yaw_rad", 0.0)),
        "height_m": float(getattr(block, "height_m", 0.0) or 0.0),
        "stack_level": int(getattr(block, "stack_level", 1) or 1),
        "stack_sizes": [str(size) for size in getattr(block, "stack_sizes", ()) or ()],
        "center_px": _floats(getattr(block, "center_px", (0.0, 0.0))),
        "is_cube": bool(getattr(block, "is_cube", True)),
        "occluded": bool(getattr(block, "occluded", False)),
        "aruco_id": getattr(block, "aruco_id", None),
        "destination": getattr(block, "destination", None),
    }
    color_lab = getattr(block, "color_lab", None)
    if color_lab is not None:
        data["color_lab"] = _floats(color_lab)
    seen_time_s = getattr(block, "seen_time_s", None)
    if seen_time_s is not None:
        data["seen_time_s"] = float(seen_time_s)
    return data


def tag_to_dict(tag) -> dict:
    return {
        "id": int(tag.id),
        "center_px": _floats(tag.center_px),
        "corners_px": np.asarray(tag.corners_px, dtype=float).round(2).tolist(),
        "hamming": getattr(tag, "hamming", None),  # bits the decoder corrected (None: ArUco does not say)
        "decision_margin": None if getattr(tag, "decision_margin", None) is None else round(float(tag.decision_margin), 2),
    }


class TelemetryPublisher(_Worker):
    """Publishes `snapshot()` into `slot` at `rate_hz`, on its own thread."""

    name = "station-telemetry"

    def __init__(self, snapshot: Callable[[], dict], slot: NewestSlot[dict], rate_hz: float) -> None:
        super().__init__()
        self.snapshot = snapshot
        self.slot = slot
        self.period_s = 1.0 / rate_hz

    def _run(self) -> None:
        next_time = time.monotonic()
        while not self._stop.is_set():
            self.slot.publish(self.snapshot())
            next_time += self.period_s
            delay = next_time - time.monotonic()
            if delay < -self.period_s:  # fell far behind (machine busy): do not burst to catch up
                next_time = time.monotonic()
                delay = 0.0
            self._stop.wait(max(0.0, delay))
