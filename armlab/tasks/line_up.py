"""line_up (DESIGN §7): per size, the six blocks in a straight, evenly spaced line in rainbow order,
shorter than 300 mm first to last; at L3 both lines at least 50 mm from every distractor.

The two lines' place is chosen at the first look among parallel pairs of lines in reach, the one
with no distractor near it and the fewest objects in its way; objects in the way go aside, then every
slot gets its block, pile tops being put on their slot or aside to uncover what is under them. The
fingers open across the line, so a release never pushes a neighbour.
"""

from __future__ import annotations

import math

from armlab.scene import COLORS
from armlab.tasks.runner import Move, Plan, TaskRunner, cubes, near

SPACING_M = 0.055  # centre to centre: 5 gaps = 275 mm < 300 mm
LINE_GAP_M = 0.075  # between the large and the small line
CORRIDOR_M = 0.045  # objects closer than this to a line's segment are in the way
DISTRACTOR_CLEARANCE_M = 0.065  # > the judge's 50 mm
SLOT_TOLERANCE_M = 0.012


def line_layouts(sizes: list[str]):
    """Candidate layouts: {size: [(x, y) of slot k for rank k]} and the line direction (rad)."""
    offsets = [k - 2.5 for k in range(6)]
    for y0 in [0.15 + 0.01 * i for i in range(16)]:
        for x0 in (-0.04, -0.02, 0.0, 0.02, 0.04):
            for sign in (1, -1):
                layout = {size: [(x0 + sign * o * SPACING_M, y0 + j * LINE_GAP_M) for o in offsets]
                          for j, size in enumerate(sizes)}
                yield layout, 0.0
    for x0 in [0.17 + 0.01 * i for i in range(12)]:
        for side in (1, -1):
            for y0 in (0.06, 0.08, 0.10):
                layout = {size: [(side * (x0 + j * LINE_GAP_M), y0 + o * SPACING_M) for o in offsets]
                          for j, size in enumerate(sizes)}
                yield layout, math.pi / 2


def segment_distance(p, a, b) -> float:
    ax, ay = a
    bx, by = b
    t = max(0.0, min(1.0, ((p[0] - ax) * (bx - ax) + (p[1] - ay) * (by - ay)) / ((bx - ax) ** 2 + (by - ay) ** 2)))
    return math.dist(p, (ax + t * (bx - ax), ay + t * (by - ay)))


def in_reach(xy) -> bool:
    return 0.14 <= math.hypot(*xy) <= 0.35


def choose_layout(runner: TaskRunner, objects: list[dict], sizes: list[str]):
    """The layout with no distractor near, all slots in reach and off the tags, and least in the way."""
    distractors = [o for o in objects if not o.get("is_cube", True)]
    best, best_cost = None, math.inf
    for layout, direction in line_layouts(sizes):
        slots = [xy for line in layout.values() for xy in line]
        if not all(in_reach(xy) and all(math.dist(xy, t) > 0.04 for t in runner.tag_centres()) for xy in slots):
            continue
        segments = [(line[0], line[-1]) for line in layout.values()]
        if any(segment_distance(d["position_m"][:2], a, b) < DISTRACTOR_CLEARANCE_M for d in distractors for a, b in segments):
            continue
        cost = sum(o.get("stack_level", 1) for o in objects
                   if any(segment_distance(o["position_m"][:2], a, b) < CORRIDOR_M for a, b in segments))
        cost += 0.1 * sum(math.hypot(*xy) for xy in slots)  # prefer lines near the arm (faster)
        if cost < best_cost:
            best, best_cost = (layout, direction), cost
    if best is None:
        raise RuntimeError("no place for the lines clear of the distractors")
    return best


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    sizes = ["large"] if level == 1 else ["large", "small"]
    chosen: dict = {}

    def policy(objects: list[dict], given_up: set) -> Plan:
        if not chosen:
            layout, direction = choose_layout(runner, objects, sizes)
            chosen.update(layout=layout, direction=direction)
            runner.reserved_m.extend(xy for line in layout.values() for xy in line)
        layout, direction = chosen["layout"], chosen["direction"]
        segments = [(line[0], line[-1]) for line in layout.values()]
        across = direction + math.pi / 2
        blocks = [b for b in cubes(objects) if b["size"] in sizes]

        def slot_of(block):
            return layout[block["size"]][COLORS.index(block["color"])]

        def placed(block) -> bool:
            return block.get("stack_level", 1) == 1 and near(block["position_m"], slot_of(block), SLOT_TOLERANCE_M)

        done = [b for b in blocks if placed(b)]
        loose = [b for b in blocks if not placed(b)]
        left = sum(int(b.get("stack_level", 1)) for b in loose)
        moves: list[Move] = []
        in_way = [o for o in objects if o not in done and o.get("is_cube", True)
                  and any(segment_distance(o["position_m"][:2], a, b) < CORRIDOR_M for a, b in segments)]

        def slot_free(xy) -> bool:
            return not any(near(o["position_m"], xy, 0.035) for o in objects)

        # Blocks whose slot is free go straight there (pile tops first: they uncover others).
        for block in sorted(loose, key=lambda b: -b.get("stack_level", 1)):
            xy = slot_of(block)
            if slot_free(xy):
                moves.append(Move(block, (xy[0], xy[1], 0.0), f"to slot {COLORS.index(block['color']) + 1} of the "
                                  f"{block['size']} line", yaw_rad=direction, finger_axis_rad=across))
        # Then whatever is in the way, and pile tops hiding blocks, go aside.
        for block in in_way + [b for b in loose if b.get("stack_level", 1) > 1 and b not in in_way]:
            x, y = runner.free_spot(objects, runner.edge_of(block))
            moves.append(Move(block, (x, y, 0.0), "out of the lines' way"))
        return Plan(moves, done=len(done), left=left, finished=not loose)

    return policy
