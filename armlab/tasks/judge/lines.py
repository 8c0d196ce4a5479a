"""line_up: each size's blocks in rainbow order along a line, neatness, and (L3) the distractors clear of
both lines."""

from __future__ import annotations

import numpy as np

from armlab.scene import SceneObject
from armlab.tasks.judge.geometry import (
    RAINBOW,
    centre_xy,
    line_distance_m,
    on_board,
    segment_distance_m,
    tls_line,
    upright,
)
from armlab.tasks.judge.rules import Rule, mm

LINE_NEAR_M = 0.030
LINE_FAR_M = 0.060
NEAT_LENGTH_M = 0.300
DISTRACTOR_CLEARANCE_M = 0.050
_LINE_UP_MAX = {1: 200, 2: 400, 3: 500}


def _score_line(order: list[SceneObject], centre, direction) -> list[Rule]:
    rules = []
    for k, block in enumerate(order):
        distance = line_distance_m(centre_xy(block), centre, direction)
        if RAINBOW.index(block.color) == k and distance <= LINE_NEAR_M:
            rules.append(Rule("line", 30, f"place {k + 1}, right colour, {mm(distance)} from the line", (block.id,)))
        elif distance <= LINE_FAR_M:
            rules.append(Rule("line", 10, f"place {k + 1} ({block.color}), {mm(distance)} from the line",
                              (block.id,)))
        else:
            rules.append(Rule("line", 0, f"place {k + 1} ({block.color}), {mm(distance)} from the line (> 60 mm)",
                              (block.id,)))
    ids = tuple(block.id for block in order)
    if len(order) != 6 or any(rule.points != 30 for rule in rules):
        rules.append(Rule("neatness", 0, "needs six blocks in rainbow order, each within 30 mm", ids))
    else:
        length = float(np.linalg.norm(centre_xy(order[-1]) - centre_xy(order[0])))
        points = 20 if length < NEAT_LENGTH_M else 0
        rules.append(Rule("neatness", points, f"first to last centre {mm(length)} (needs < 300 mm)", ids))
    return rules


def score_line_up(level, objects, blocks):
    sizes = ("large",) if level == 1 else ("large", "small")
    rules: list[Rule] = []
    segments = []
    for size in sizes:
        members = [b for b in blocks if b.size == size and upright(b) and on_board(b)]
        if not members:
            rules.append(Rule("line", 0, f"no upright {size} block on the board"))
            continue
        centre, axis = tls_line([b.position_m for b in members])
        best: list[Rule] | None = None
        for direction in (axis, -axis):
            order = sorted(members, key=lambda b: (float((centre_xy(b) - centre) @ direction), b.id))
            candidate = _score_line(order, centre, direction)
            if best is None or sum(r.points for r in candidate) > sum(r.points for r in best):
                best = candidate
        rules.extend(best)
        along = [float((centre_xy(b) - centre) @ axis) for b in members]
        segments.append((centre + min(along) * axis, centre + max(along) * axis))
    if level == 3:
        distractors = [obj for obj in objects if obj.type != "block"]
        ids = tuple(obj.id for obj in distractors)
        if len(segments) < len(sizes):
            rules.append(Rule("distractors", 0, "needs both lines to exist", ids))
        else:
            near = [(min(segment_distance_m(centre_xy(obj), a, b) for a, b in segments), obj.id) for obj in distractors]
            close = sorted(item for item in near if item[0] < DISTRACTOR_CLEARANCE_M)
            if close:
                rules.append(Rule("distractors", 0, f"{close[0][1]} is {mm(close[0][0])} from a line (< 50 mm)",
                                  tuple(obj_id for _, obj_id in close)))
            else:
                rules.append(Rule("distractors", 100, "every distractor is >= 50 mm from both lines", ids))
    return rules, _LINE_UP_MAX[level]
