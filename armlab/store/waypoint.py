"""A taught pose (Waypoint): the unit of every program, its step tree (program_tree) and the teach draft."""

from __future__ import annotations

import math
from dataclasses import dataclass

from armlab.errors import InvalidInput

MAX_DWELL_S = 3600.0  # the longest dwell or moving time of one waypoint


@dataclass(frozen=True)
class Waypoint:
    """A taught pose: joint positions (rad), the gripper command at that pose ('grasp'|'release'),
    how long to hold still there (dwell_s) and, optionally, how long the move to it should take
    (moving_time_s; None = as fast as the speed override and the joint limits allow)."""

    joints_rad: tuple[float, ...]
    gripper: str
    dwell_s: float = 0.0
    moving_time_s: float | None = None

    def __post_init__(self) -> None:
        if not self.joints_rad or not all(math.isfinite(float(value)) for value in self.joints_rad):
            raise InvalidInput("Waypoint.joints_rad must be a non-empty list of finite numbers")
        if self.gripper not in ("grasp", "release"):
            raise InvalidInput(f"Waypoint.gripper must be 'grasp' or 'release', not {self.gripper!r}")
        dwell = float(self.dwell_s)
        if not math.isfinite(dwell) or not 0.0 <= dwell <= MAX_DWELL_S:
            raise InvalidInput(f"Waypoint.dwell_s must be from 0 to {MAX_DWELL_S:g} s, not {self.dwell_s!r}")
        if self.moving_time_s is not None:
            moving = float(self.moving_time_s)
            if not math.isfinite(moving) or not 0.0 < moving <= MAX_DWELL_S:
                raise InvalidInput(f"Waypoint.moving_time_s must be above 0 and at most {MAX_DWELL_S:g} s, not {self.moving_time_s!r}")
            object.__setattr__(self, "moving_time_s", moving)
        object.__setattr__(self, "joints_rad", tuple(float(value) for value in self.joints_rad))
        object.__setattr__(self, "dwell_s", dwell)

    def to_dict(self) -> dict:
        return {"joints_rad": list(self.joints_rad), "gripper": self.gripper, "dwell_s": self.dwell_s, "moving_time_s": self.moving_time_s}

    @classmethod
    def from_dict(cls, item: dict) -> Waypoint:
        """From to_dict()'s form (dwell_s and moving_time_s optional); KeyError/TypeError/ValueError if invalid."""
        if not isinstance(item, dict):
            raise TypeError("a waypoint must be a JSON object")
        return cls(tuple(item["joints_rad"]), item["gripper"], item.get("dwell_s") or 0.0, item.get("moving_time_s"))
