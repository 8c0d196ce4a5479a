"""The Camera interface: colour plus optional depth aligned to colour.

Images: color_bgr (H, W, 3) uint8 BGR (OpenCV order); depth_mm (H, W) uint16 millimetres along the
optical axis, 0 = no reading. Timestamps are time.time() at capture. "Newest value wins": read_latest
never waits and refuses stale frames; async_read returns the newest frame not yet consumed.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels with OpenCV's distortion model (k1, k2, p1, p2, k3)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    dist: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)

    @property
    def K(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class Frame:
    """One capture. depth_mm is None for colour-only cameras. sequence increases by one per frame.

    arm_joints_rad: the arm's measured joints (dof,) when the frame was captured, and gripper_closed:
    whether the gripper was commanded closed (a block may be between its fingers), for perception's
    robot self-filter. The simulated camera fills both exactly at render time; a real camera leaves
    them None and the station fills them from the arm and gripper when the frame arrives.
    """

    color_bgr: np.ndarray
    depth_mm: np.ndarray | None
    timestamp_s: float
    sequence: int
    intrinsics: Intrinsics = field(repr=False, default=None)  # type: ignore[assignment]
    arm_joints_rad: np.ndarray | None = field(repr=False, default=None)
    gripper_closed: bool | None = None


class Camera(abc.ABC):
    """An RGB(-D) camera with a reader thread. Same connect/close/error contract as Arm."""

    @abc.abstractmethod
    def connect(self) -> None: ...

    @abc.abstractmethod
    def close(self) -> None: ...

    @property
    @abc.abstractmethod
    def is_connected(self) -> bool: ...

    @property
    @abc.abstractmethod
    def intrinsics(self) -> Intrinsics: ...

    @abc.abstractmethod
    def read(self) -> Frame:
        """Block until the next new frame and return it."""

    @abc.abstractmethod
    def async_read(self, timeout_ms: float = 200.0) -> Frame:
        """The newest frame not yet returned by async_read, waiting up to timeout_ms; else TimeoutError."""

    @abc.abstractmethod
    def read_latest(self, max_age_ms: float = 500.0) -> Frame:
        """The newest frame without waiting; TimeoutError if none or older than max_age_ms."""
