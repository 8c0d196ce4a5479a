"""What the gripper holds, as the station remembers it after a pick: a typed value, not a wire dict."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class HeldBlock:
    """The block the last pick put in the gripper: its edge (m; the body check keeps it clear of the arm, a place plans
    with it), its colour and size when the pick knew them, and its yaw (rad) when the grab measured it."""

    edge_m: float
    color: str | None = None
    size: str | None = None
    yaw_rad: float | None = None
