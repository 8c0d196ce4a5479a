"""Stacking events: pick_stack (columns of three or more on a tag, the gripper kept in its box), stack_high
(columns of one size, the rainbow column) and to_the_sky (the tallest tower)."""

from __future__ import annotations

import numpy as np

from armlab.errors import InvalidInput
from armlab.tasks.judge.geometry import RAINBOW, centre_xy, columns, upright
from armlab.tasks.judge.rules import Rule, bonus_rule, mm, tipped
from armlab.vision import load_perception_config

TAG_RADIUS_M = 0.030  # pick_stack: bottom block centre to a tag centre
PICK_STACK_MIN_HEIGHT = 3
GRIPPER_BOX_M = {"x_abs_max": 0.260, "y_min": -0.035, "y_max": 0.285, "z_max": 0.300}
_STACK_HIGH_MAX = {1: 250, 2: 500}


def tower_points(height: int) -> int:
    """to_the_sky: blocks 1-8 of the column score 30 each, 9 and up 50 each."""
    return 30 * min(height, 8) + 50 * max(height - 8, 0)


def board_tag_centres_m(workcell: str | None = None) -> tuple[tuple[float, float], ...]:
    """pick_stack's tag centres (x, y), from the board layout in configuration (`workcell`'s; None = the default)."""
    return tuple((float(x), float(y)) for x, y in load_perception_config(workcell=workcell).tags.board_tags.values())


def _gripper_left_box(path: np.ndarray | None) -> str:
    if path is None:
        return "gripper path not recorded, so staying inside the box is unproven"
    box = GRIPPER_BOX_M
    outside = ((np.abs(path[:, 0]) > box["x_abs_max"]) | (path[:, 1] < box["y_min"]) | (path[:, 1] > box["y_max"])
               | (path[:, 2] > box["z_max"]))
    if np.any(outside):
        x, y, z = path[int(np.argmax(outside))]
        return f"gripper left the box at ({mm(x)}, {mm(y)}, {mm(z)})"
    return ""


def score_pick_stack(level, blocks, within_limit, limit_s, path, tags):
    placement: dict[str, tuple[int, float]] = {}
    for stack in columns(blocks):
        tag_distance = float(np.min(np.linalg.norm(tags - centre_xy(stack[0]), axis=1)))
        for block in stack:
            placement[block.id] = (len(stack), tag_distance)
    rules = []
    for block in blocks:
        if not upright(block):
            rules.append(tipped(block, "stacked"))
        elif block.id not in placement:
            rules.append(Rule("stacked", 0, "in no column (neither on the board nor on a column's top)", (block.id,)))
        elif placement[block.id][0] < PICK_STACK_MIN_HEIGHT:
            rules.append(Rule("stacked", 0, f"in a column of {placement[block.id][0]} (< 3)", (block.id,)))
        elif placement[block.id][1] > TAG_RADIUS_M:
            rules.append(Rule("stacked", 0, f"column's bottom is {mm(placement[block.id][1])} from the nearest tag "
                                            f"centre (> 30 mm)", (block.id,)))
        else:
            rules.append(Rule("stacked", 40, f"upright in a column of {placement[block.id][0]} on a tag", (block.id,)))
    bonus = bonus_rule(20 * level, within_limit, limit_s, rules, _gripper_left_box(path))
    return [*rules, bonus], 40 * len(blocks) + 20 * level


def score_stack_high(level, blocks):
    sizes = ("large",) if level == 1 else ("large", "small")
    rules = []
    for size in sizes:
        of_size = [b for b in blocks if b.size == size]
        stacks = columns([b for b in of_size if upright(b)])
        for stack in stacks:
            ids = tuple(b.id for b in stack)
            points = sum(10 * n for n in range(1, len(stack) + 1))
            rules.append(Rule("column", points, f"{len(stack)} upright {size} blocks: 10 x n for block n", ids))
            if tuple(b.color for b in stack) == RAINBOW:
                rules.append(Rule("rainbow", 40, f"all six {size} blocks in rainbow order, red at the bottom", ids))
        stacked = {b.id for stack in stacks for b in stack}
        loose = tuple(b.id for b in of_size if b.id not in stacked)
        if loose:
            rules.append(Rule("column", 0, f"{size} blocks in no column of upright {size} blocks", loose))
    return rules, _STACK_HIGH_MAX[level]


def score_to_the_sky(blocks, blocks_available):
    large = [b for b in blocks if b.size == "large"]
    available = len(large) if blocks_available is None else blocks_available
    if isinstance(available, bool) or not isinstance(available, (int, np.integer)) or available < len(large):
        raise InvalidInput(f"judge: blocks_available must be an int >= the {len(large)} large blocks in truth, "
                         f"got {blocks_available!r}")
    stacks = columns([b for b in large if upright(b)])
    tallest = max(stacks, key=len) if stacks else ()
    points = tower_points(len(tallest))
    detail = f"tallest column of upright large blocks: {len(tallest)} (blocks 1-8 x 30, 9 and up x 50)"
    return [Rule("tower", points, detail, tuple(b.id for b in tallest))], tower_points(int(available))
