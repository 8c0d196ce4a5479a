"""Where the gripper went and when: the motion gate's record of its recent motions (the gripper's sampled path and
each motion's end), so a detection or remembered depth seen at a spot before a motion through it counts as stale.
Times are wall time, like the frames' timestamps they are compared with. Owned by the gate (motion.py)."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from armlab.devices.arm import JointTrajectory

CHANGE_ABOVE_M = 0.06  # the gripper point this close above a spot's surface can have changed it (fingers, a held block)
MOTION_MEMORY = 256  # how many recent arm motions the gate remembers for stale-perception checks


class MotionRecord:
    """The last MOTION_MEMORY motions as (end time_s, [xmin, ymin, xmax, ymax, x, y, z of the gripper's sampled
    path...]) and the last change that may have changed any spot. model: the ArmModel (fk); wall_s: the time source."""

    def __init__(self, model: Any, wall_s: Callable[[], float] = time.time) -> None:
        self._model, self._wall_s = model, wall_s
        self._lock = threading.Lock()
        self._motions: list[tuple[float, np.ndarray]] = []
        self._changed_everywhere_s = -math.inf  # the last change that may have changed any spot (note_change_everywhere)

    def now_s(self) -> float:
        """The record's time now (wall time)."""
        return self._wall_s()

    def swept_box(self, trajectory: JointTrajectory) -> np.ndarray:
        """[xmin, ymin, xmax, ymax] of the gripper point along a trajectory, then the sampled points' x, y, z
        (for changed_at_since; sampled, no lock needed)."""
        positions = trajectory.positions_rad
        tips = self._model.fk(positions[:: max(1, len(positions) // 40)])[:, :3, 3]
        tips = np.vstack([tips, self._model.fk(positions[-1])[:3, 3]])
        return np.concatenate([tips[:, :2].min(axis=0), tips[:, :2].max(axis=0), tips.ravel()])

    def add(self, duration_s: float, swept_box: np.ndarray) -> tuple[float, np.ndarray]:
        """A motion sent now that lasts duration_s and sweeps swept_box; returns its entry (see last())."""
        entry = (self._wall_s() + duration_s, swept_box)
        with self._lock:
            self._motions.append(entry)
            del self._motions[:-MOTION_MEMORY]
        return entry

    def last(self) -> tuple[float, np.ndarray] | None:
        """The newest entry (an object replaced, never changed: `is` tells whether another motion came since)."""
        with self._lock:
            return self._motions[-1] if self._motions else None

    def last_end_s(self) -> float:
        """When the newest motion ends (wall time; -inf before any)."""
        last = self.last()
        return -math.inf if last is None else last[0]

    def ended_now(self) -> None:
        """The newest motion has ended now (a job's step arrived): its end time is now."""
        with self._lock:
            if self._motions:
                self._motions[-1] = (self._wall_s(), self._motions[-1][1])

    def moved_over_since(self, point_m, since_s: float, radius_m: float = 0.06) -> bool:
        """True if a motion that ended after `since_s` (wall time, like frame timestamps) swept the gripper
        within radius_m of point_m in x-y: a detection seen at since_s may be stale there."""
        x, y = float(point_m[0]), float(point_m[1])
        with self._lock:
            motions = list(self._motions)
        for end_s, box in motions:
            xmin, ymin, xmax, ymax = box[:4]
            if end_s > since_s and xmin - radius_m <= x <= xmax + radius_m and ymin - radius_m <= y <= ymax + radius_m:
                return True
        return False

    def changed_at_since(self, point_m, since_s: float, radius_m: float = 0.06, above_m: float = CHANGE_ABOVE_M) -> bool:
        """True if after `since_s` the gripper came down within above_m of point_m's height within radius_m of it
        in x-y (a motion through the spot, a drop or a grab there, a gripper opened or closed over it), or a change
        everywhere was noted (note_change_everywhere): what was seen there at since_s may have changed."""
        spot = np.asarray(point_m[:3], float)
        with self._lock:
            if self._changed_everywhere_s > since_s:
                return True
            motions = list(self._motions)
        for end_s, box in motions:
            points = np.asarray(box[4:], float).reshape(-1, 3)  # the gripper's sampled path
            if end_s > since_s and np.any((np.linalg.norm(points[:, :2] - spot[:2], axis=1) <= radius_m) & (points[:, 2] < spot[2] + above_m)):
                return True
        return False

    @property
    def changed_everywhere_s(self) -> float:
        with self._lock:
            return self._changed_everywhere_s

    def note_change_everywhere(self) -> None:
        """A change that may have changed any spot (a new scene, a checkerboard held up or put away, the camera
        knocked): for changed_at_since, what was seen before it and is hidden since is unknown everywhere."""
        with self._lock:
            self._changed_everywhere_s = self._wall_s()

    def note_gripper_change_at(self, point_m) -> None:
        """A grasp or release with the gripper point at point_m: whatever it held falls straight down, so every spot
        below it may have changed (for changed_at_since; no motion of the arm)."""
        x, y = float(point_m[0]), float(point_m[1])
        with self._lock:
            self._motions.append((self._wall_s(), np.array([x, y, x, y, x, y, -np.inf])))
            del self._motions[:-MOTION_MEMORY]
