"""Columns (stacks) that a job builds at a fixed spot.

What stands there is measured at every look: the column's height from the depth image at its base
(a ray cast onto the depth surface, which works however tall the column is) and its top block's
centre from the detection there, when there is one. What the column holds (colours, bottom-up) is
remembered from what the job put there, trimmed when the measured height says blocks fell.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from armlab import skills
from armlab.tasks.policy import near
from armlab.tasks.seen import PlacedBlock, Seen, StandingObject
from armlab.vision.block import Block

COLUMN_RADIUS_M = 0.03  # a detection this close to the base (x-y) is the column's top (a tall column leans a little)
HEIGHT_TOLERANCE_M = 0.012


@dataclass
class Column:
    """A stack built bottom-up at base_xy_m."""

    name: str
    base_xy_m: tuple[float, float]
    placed: list[PlacedBlock] = field(default_factory=list)  # blocks put here, bottom-up
    top: Seen | None = None  # what stands highest at its base at the newest look (a detection, or a column seen by depth only)
    height_m: float = 0.0  # measured height of the column's top face (remembered when unmeasured)
    unmeasured: bool = False  # the newest look could not measure the height (see observe)

    def observe(self, objects: list[Seen], measure_height: Callable[[tuple[float, float]], float | None]) -> None:
        """Update from a look: the top detection near the base and the measured height. A height of None
        (the camera sees neither a top nor the board there: a column whose top is outside the image hides
        its own base, e.g. six blocks at (-150, -120) mm on the RX200) keeps what the job put there, and
        the column stands as high as those blocks."""
        tops = [o for o in objects if near(o.position_m, self.base_xy_m, COLUMN_RADIUS_M)]
        self.top = max(tops, key=lambda o: o.position_m[2]) if tops else None
        measured = measure_height(self.base_xy_m)
        self.unmeasured = measured is None
        self.height_m = sum(block.edge_m for block in self.placed) if measured is None else measured
        kept, stacked_m = [], 0.0
        for block in self.placed:  # keep what the measured height still holds
            if stacked_m + block.edge_m > self.height_m + HEIGHT_TOLERANCE_M:
                break
            kept.append(block)
            stacked_m += block.edge_m
        self.placed = kept

    @property
    def height(self) -> int:
        """How many blocks it holds: remembered, else the top detection's measured level."""
        if self.placed:
            return len(self.placed)
        return 0 if self.top is None or self.height_m < 0.005 else int(self.top.stack_level)

    def top_color(self) -> str | None:
        if self.placed:
            return self.placed[-1].color
        return None if self.top is None else self.top.color

    def surface_m(self) -> tuple[float, float, float]:
        """Where the next block's bottom centre goes: on the measured top (its detected centre when
        the detection agrees with the measured height, else above the base)."""
        x, y = self.base_xy_m
        if self.top is not None and abs(self.top.position_m[2] - self.height_m) < HEIGHT_TOLERANCE_M:
            x, y = self.top.position_m[:2]
        return (float(x), float(y), float(self.height_m if self.height_m > 0.005 else 0.0))

    def stand_in(self) -> StandingObject | None:
        """An obstacle for a column that stands but that the newest look could neither measure nor detect
        (an object no policy picks, as TaskRunner.unseen_columns makes), else None."""
        if not self.unmeasured or self.top is not None or self.height_m <= 0.005:
            return None
        return StandingObject.at(self.base_xy_m, self.height_m)

    def holds(self, block: Seen) -> bool:
        """True if `block` (a detection) is this column's top."""
        return self.top is not None and block is self.top

    def add(self, block: Block, edge_m: float) -> None:
        self.placed.append(PlacedBlock.of(block, edge_m))


def unseen_as_none(runner) -> Callable[[tuple[float, float]], float | None]:
    """The runner's height measurement, None where the camera sees nothing at (x, y), not even the board
    (for Column.observe)."""
    return lambda xy_m: skills.surface_height_m(runner.station, xy_m, unseen=None)
