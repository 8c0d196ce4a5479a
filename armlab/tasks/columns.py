"""Columns (stacks) that a job builds at a fixed spot: what is there is read from the newest look
(the measured top and pile height), what it holds from memory of what the job put there, trimmed
when the measured pile is lower than remembered (a block fell)."""

from __future__ import annotations

from dataclasses import dataclass, field

from armlab.tasks.runner import near

COLUMN_RADIUS_M = 0.02  # a detection this close to the base (x-y) is the column's top


@dataclass
class Column:
    """A stack built bottom-up at base_xy_m."""

    name: str
    base_xy_m: tuple[float, float]
    placed: list[dict] = field(default_factory=list)  # blocks put here, bottom-up (wire dicts)
    top: dict | None = None  # the detection of its top block at the newest look

    def observe(self, objects: list[dict]) -> None:
        """Update from a look: the top detection at the base and the measured pile height."""
        tops = [o for o in objects if near(o["position_m"], self.base_xy_m, COLUMN_RADIUS_M + 0.01)]
        self.top = max(tops, key=lambda o: o["position_m"][2]) if tops else None
        level = 0 if self.top is None else int(self.top.get("stack_level", 1))
        if level < len(self.placed):
            del self.placed[level:]

    @property
    def height(self) -> int:
        return 0 if self.top is None else int(self.top.get("stack_level", 1))

    def surface_m(self) -> tuple[float, float, float]:
        """Where the next block's bottom centre goes: on the measured top, else the base on the board."""
        if self.top is None:
            return (self.base_xy_m[0], self.base_xy_m[1], 0.0)
        x, y, z = self.top["position_m"]
        if not near((x, y), self.base_xy_m, COLUMN_RADIUS_M):
            x, y = self.base_xy_m
        return (float(x), float(y), float(z))

    def holds(self, block: dict) -> bool:
        """True if `block` (a detection) is this column's top."""
        return self.top is not None and block is self.top
