"""What a job's policy and the runner (runner.py) say to each other: the policy's answer (a Plan of candidate
Moves, best first), the Policy type, NoFreeSpot (a policy leaves an object where it is), and the pure helpers
policies share over a look's objects (seen.py: Blocks and StandingObjects): cubes, blocks counted, nearness, the finger
axis away from neighbours."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from armlab.tasks.seen import Seen
from armlab.vision.block import Block


class NoFreeSpot(RuntimeError):
    """free_spot found no spot: the policy leaves the object where it is, with this reason, and goes on."""


@dataclass(frozen=True)
class Move:
    """Pick `block` (a detection) and set it down with its bottom centre at `to_m`
    (x, y, surface z) with yaw `yaw_rad` (None: keep the block's own yaw). `why` is shown to the operator."""

    block: Block
    to_m: tuple[float, float, float]
    why: str
    yaw_rad: float | None = 0.0
    finger_axis_rad: float | None = None  # world direction the fingers open along when releasing
    side_ok: bool = False  # may be set down with the gripper horizontal when too high for top-down
    max_tilt_rad: float = math.radians(5.0)  # how far from top-down the gripper may be when it releases
    grasp_pitches_rad: tuple[float, ...] = ()  # pick and place at the first that plans, fingers horizontal (skills.side_grasp)
    on_placed: Callable[[float], None] | None = field(default=None, compare=False)  # called with the edge once placed

    def key(self) -> tuple:
        """Identifies "the same move" across looks (attempt counting): the block, by its kind and where it is."""
        b = self.block
        return (b.color, b.size, b.is_cube, round(float(b.position_m[0]), 2), round(float(b.position_m[1]), 2))


@dataclass(frozen=True)
class Plan:
    """A policy's answer: candidate moves (best first), and how many target blocks are done / left."""

    moves: list[Move]
    done: int
    left: int
    finished: bool = False


Policy = Callable[[list[Seen], set], Plan]


def cubes(objects: list[Seen]) -> list[Block]:
    """The detections that are blocks (not distractors, nothing unseen)."""
    return [o for o in objects if o.is_cube]


def blocks_seen(objects: list[Seen]) -> int:
    """How many blocks a look accounts for: every cube detection with the blocks under it (stack_level)."""
    return sum(max(1, int(o.stack_level)) for o in cubes(objects))


def confirm_finish(plan: Plan, seen_now: int, seen_before: int | None) -> bool:
    """Whether a look that would end the job must be repeated first: it sees fewer blocks than the look
    before it. Blocks do not vanish; a detection that misses one (a frame caught mid-exposure, a busy
    machine) would otherwise end the job counting it neither done nor left (CI: pick_sort done 2 of 3)."""
    return plan.finished and seen_before is not None and seen_now < seen_before


def near(a, b, radius_m: float) -> bool:
    return math.dist(a[:2], b[:2]) <= radius_m


FINGER_REACH_M = 0.075  # neighbours closer than this (centre to centre) can meet an opening finger


def finger_axis_away(point_m, yaw_rad: float, objects: list[Seen], exclude: Seen | None = None) -> float | None:
    """Of the two finger directions that close on a block of yaw yaw_rad, the one more across the
    direction to the nearest neighbour within FINGER_REACH_M (None when nobody is that close)."""
    others = [o for o in objects if o is not exclude and 1e-3 < math.dist(o.position_m[:2], point_m[:2]) < FINGER_REACH_M]
    if not others:
        return None
    nearest = min(others, key=lambda o: math.dist(o.position_m[:2], point_m[:2]))
    toward = math.atan2(nearest.position_m[1] - point_m[1], nearest.position_m[0] - point_m[0])
    return max((yaw_rad, yaw_rad + math.pi / 2), key=lambda axis: abs(math.sin(axis - toward)))
