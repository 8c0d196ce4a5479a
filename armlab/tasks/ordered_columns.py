"""Columns in rainbow order, one per block size (sort_stack L2/L3, stack_high, stack_here).

The next block for a column is the lowest rainbow rank of its size still loose. A pile whose top is
not next hides blocks: its top is put aside on a free spot so the blocks under it can be seen. A
column whose top outranks a loose block of its size (a block was hidden, or fell) gives its top back.
With `in_the_way` (tall columns, stack_high), a loose block that a column would keep from the arm or
hide from the camera once its next block is on is moved out of the way first (or straight onto its
own column, when it is next there), and blocks are put aside only where no full column is in the way.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from armlab.scene import COLORS
from armlab.tasks.columns import Column
from armlab.tasks.policy import Move, NoFreeSpot, Plan, cubes
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block

RANK = {color: rank for rank, color in enumerate(COLORS)}
COLUMN_MAX_TILT_RAD = math.radians(20.0)  # the top of a tall column is reachable only slightly tilted
ON_COLUMN_RADIUS_M = 0.045  # a block this close to a column's base and off the board stands on the column

# in_the_way(base_xy_m, size, column_height_m, point_xy_m): True when a column of that size and height
# at base_xy_m keeps the arm from a block at point_xy_m or hides it from the camera.
InTheWay = Callable[[tuple[float, float], str, float, tuple[float, float]], bool]


def pile_sizes(block: Block) -> list[str]:
    return list(block.stack_sizes) or [block.size] * int(block.stack_level)


def make_ordered_policy(runner: TaskRunner, bases: dict[str, tuple[float, float]] | None, *,
                        aside_region=None, choose_bases=None, keep=lambda block: True, in_the_way: InTheWay | None = None):
    """A policy building one rainbow-ordered column per size at bases[size] (or choose_bases(objects)
    at the first look). keep(block) selects the blocks the job moves (the others are obstacles).
    in_the_way: see the module docstring (None: columns are never in the way)."""
    columns: dict[str, Column] = {}

    def policy(objects: list[Seen], given_up: set) -> Plan:
        if not columns:
            chosen = bases if bases is not None else choose_bases(objects)
            columns.update({size: Column(f"{size} column", xy) for size, xy in chosen.items()})
            runner.reserved_m.extend(chosen.values())
        for column in columns.values():
            column.observe(objects, runner.height_at)

        def on_a_column(block) -> bool:  # part of a column, not loose (a leaning column shows a strip of a lower block)
            return any(math.dist(block.position_m[:2], c.base_xy_m) < ON_COLUMN_RADIUS_M
                       and block.position_m[2] > runner.edge_of(block) + 0.01 for c in columns.values())

        # A block of a colour outside the rainbow (perception's 'unknown', a taught 'pink') has no place in a column: an obstacle.
        blocks = [b for b in cubes(objects) if keep(b) and b.size in columns and b.color in RANK]
        tops = {id(c.top) for c in columns.values() if c.top is not None}
        loose = [b for b in blocks if id(b) not in tops and (in_the_way is None or not on_a_column(b))]
        hidden = {size: sum(pile_sizes(b)[:-1].count(size) for b in loose) for size in columns}
        done = sum(c.height for c in columns.values())
        left = sum(len(pile_sizes(b)) for b in loose)
        allowed = None
        if in_the_way is not None:
            full_m = {size: runner.edges_m[size] * (column.height + sum(pile_sizes(b).count(size) for b in loose))
                      for size, column in columns.items()}

            def allowed(xy, full_m=full_m) -> bool:  # no column, once full, in the way of a block put here
                return not any(in_the_way(c.base_xy_m, size, full_m[size], xy) for size, c in columns.items())

        moves: list[Move] = []
        # A column whose top outranks a loose block of its size gives the top back (put aside).
        for size, column in columns.items():
            top_color = column.top_color()
            if column.top is None or top_color not in RANK:
                continue
            lower = [b for b in loose if b.size == size and RANK[b.color] < RANK[top_color]]
            if lower:
                move = aside(runner, column.top, objects, aside_region, "out of order: make room for the "
                             f"{lower[0].color} block", allowed)
                if move is not None:
                    moves.append(Move(move.block, move.to_m, move.why, on_placed=lambda edge, c=column: c.placed.pop() if c.placed else None))
        next_moves: dict[int, Move] = {}
        for block in sorted(loose, key=lambda b: (RANK[b.color], -b.stack_level)):
            size = block.size
            column = columns[size]
            same = [b for b in loose if b.size == size]
            is_next = RANK[block.color] == min(RANK[b.color] for b in same) and hidden[size] == 0
            if is_next:
                yaw = column.top.yaw_rad if column.top is not None else 0.0
                next_moves[id(block)] = Move(block, column.surface_m(), f"next on the {column.name}", yaw_rad=yaw,
                                             max_tilt_rad=COLUMN_MAX_TILT_RAD,
                                             on_placed=lambda edge, c=column, b=block: c.add(b, edge))
        if in_the_way is not None:
            # Before a column grows, what it would then keep from the arm or the camera goes first.
            for block in sorted(loose, key=lambda b: -b.stack_level):
                blocking = [c for size, c in columns.items()
                            if in_the_way(c.base_xy_m, size, c.height_m + runner.edges_m[size], block.position_m[:2])]
                if not blocking:
                    continue
                if id(block) in next_moves:
                    moves.append(next_moves[id(block)])
                else:
                    moves.append(aside(runner, block, objects, aside_region, f"out of the {blocking[0].name}'s way", allowed))
        moves.extend(next_moves.values())
        for block in sorted(loose, key=lambda b: -b.stack_level):
            if block.stack_level > 1:
                moves.append(aside(runner, block, objects, aside_region, "uncover the pile under it", allowed))
        return Plan([m for m in moves if m is not None], done=done, left=left, finished=not loose)

    return policy


def aside(runner: TaskRunner, block: Block, objects: list[Seen], region, why: str,
          allowed: Callable[[tuple[float, float]], bool] | None = None) -> Move | None:
    """Move `block` to a free spot on the board: in region (None: free_spot's default), else anywhere in the
    arm's reach (REACH_REGION_M), first where allowed(x, y) (when given), then anywhere; None, with the reason
    said once, when the board has no free spot at all (the job goes on with its other moves)."""
    try:
        x, y = runner.free_spot_in_reach(objects, runner.edge_of(block), region, (allowed, None) if allowed is not None else (None,))
    except NoFreeSpot:
        runner.note_once(f"left the {block.color} {block.size} block at ({block.position_m[0] * 1000:.0f}, "
                         f"{block.position_m[1] * 1000:.0f}) mm where it is: no free spot on the board to put it aside")
        return None
    return Move(block, (x, y, 0.0), why)
