"""pick_sort (DESIGN §7): every block to the negative half-plane, small ones at x < 0, large at x > 0.

Blocks go to slots in two rows at y < 0, one side per size, away from the calibration tags; pile tops
are taken first, so the blocks under them show up at the next look. The arm looks from the overhead
pose: parked low (the sleep pose) it hides, or its self-filter masks, blocks just in front of it.
"""

from __future__ import annotations

from collections.abc import Callable

from armlab.tasks.look_poses import seeing_look_pose
from armlab.tasks.policy import Move, Plan, cubes, near
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block

# The innermost slots 100 mm from x = 0: at 90 mm a large block was partly hidden by the arm at the look
# pose once the arm sagged 0.03 rad (then neither detected nor counted done).
SLOT_XS_M = (0.10, 0.1625, 0.225, 0.2875, 0.35)
SLOT_YS_M = (-0.065, -0.13)
SLOT_FREE_RADIUS_M = 0.04
SLOT_EMPTY_HEIGHT_M = 0.010  # a slot whose measured height is above this holds something


def side_sign(size: str) -> float:
    """+1 for large (x > 0), -1 for small (x < 0)."""
    return 1.0 if size == "large" else -1.0


def is_sorted(block: Block) -> bool:
    x, y = block.position_m[:2]
    return y < 0.0 and x * side_sign(block.size) > 0.0 and block.stack_level == 1


def slots(size: str) -> list[tuple[float, float]]:
    sign = side_sign(size)
    return [(sign * x, y) for y in SLOT_YS_M for x in SLOT_XS_M]


def policy(objects: list[Seen], given_up: set, standing_at: Callable[[tuple[float, float]], float] | None = None) -> Plan:
    """The next moves. standing_at(xy): the measured height of what stands at a spot (None: not measured);
    a slot is free when no detection is near it and nothing measurably stands on it (a block the arm
    partly hides at the look goes undetected, but the depth image still shows it there)."""
    blocks = cubes(objects)
    done = [b for b in blocks if is_sorted(b)]
    todo = [b for b in blocks if not is_sorted(b)]
    hidden = sum(b.stack_level - 1 for b in todo)
    moves, claimed, occupied = [], [], []

    def free(slot) -> bool:
        if any(near(o.position_m, slot, SLOT_FREE_RADIUS_M) for o in objects) or any(near(c, slot, SLOT_FREE_RADIUS_M) for c in claimed):
            return False
        if slot in occupied or standing_at is not None and standing_at(slot) > SLOT_EMPTY_HEIGHT_M:
            occupied.append(slot)
            return False
        return True

    # Pile tops first (they uncover blocks), then nearest the board's middle.
    for block in sorted(todo, key=lambda b: (-b.stack_level, abs(b.position_m[0]))):
        target = next((s for s in slots(block.size) if free(s)), None)
        if target is None:
            continue
        claimed.append(target)
        moves.append(Move(block, (target[0], target[1], 0.0), f"to the {block.size} side"))
    return Plan(moves, done=len(done), left=len(todo) + hidden, finished=not todo)


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    """The policy, with the runner looking from the overhead pose and slots checked in the depth image."""
    runner.look_pose_rad = seeing_look_pose(runner.station)
    return lambda objects, given_up: policy(objects, given_up, runner.height_at)
