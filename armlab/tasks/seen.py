"""What a job's look hands its policy: the detected blocks (armlab.vision Block) and the StandingObjects the
job knows stand on the board where no block was detected; and PlacedBlock, what a job remembers putting on a
column. Typed, so a policy reads block.is_cube, never a wire dict's o.get("is_cube", True) (issue 20, item 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from armlab.vision.block import Block


@dataclass(frozen=True, eq=False)
class StandingObject:
    """Something standing at position_m (its top centre, world metres) that no policy picks: a column the
    detector missed but depth measures (a column too tall for it), or a column a job built and can no longer see.

    It answers what the jobs ask of any object before they filter the cubes (where, colour, size, level, yaw) with
    "none": not a cube, no colour, no size."""

    position_m: np.ndarray
    color: str | None = None
    size: str | None = None
    yaw_rad: float = 0.0
    stack_level: int = 0
    is_cube: bool = False

    @classmethod
    def at(cls, xy_m, height_m: float) -> StandingObject:
        """An object standing height_m high at board point xy_m."""
        return cls(np.array([float(xy_m[0]), float(xy_m[1]), float(height_m)]))


# What a look holds: a detection, or an object known to stand there.
Seen = Block | StandingObject


def is_unseen(obj: Seen) -> bool:
    """True for an object the detector did not report (a StandingObject): an obstacle, never a move candidate."""
    return isinstance(obj, StandingObject)


@dataclass(frozen=True)
class PlacedBlock:
    """A block a job put on a column: its colour and size as detected when picked, and its edge (m)."""

    color: str | None
    size: str | None
    edge_m: float

    @classmethod
    def of(cls, block: Block, edge_m: float) -> PlacedBlock:
        return cls(block.color, block.size, float(edge_m))
