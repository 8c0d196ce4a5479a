"""line_up (DESIGN §7): per size, the six blocks in a straight, evenly spaced line in rainbow order,
shorter than 300 mm first to last; at L3 both lines at least 50 mm from every distractor.

The two lines' place is chosen at the first look among parallel pairs of lines in reach, the one
with no distractor near it and the fewest objects in its way; objects in the way go aside, then every
slot gets its block, pile tops being put on their slot or aside to uncover what is under them. The
fingers open across the line, so a release never pushes a neighbour.
"""

from __future__ import annotations

import math

import numpy as np

from armlab import skills
from armlab.scene import COLORS
from armlab.tasks.policy import FINGER_REACH_M, Move, NoFreeSpot, Plan, cubes, near
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen, is_unseen

SPACING_M = 0.055  # centre to centre: 5 gaps = 275 mm < 300 mm
LINE_GAP_M = 0.075  # between the large and the small line
CORRIDOR_M = 0.07  # objects closer than this to a line segment are in the way (an opening finger reaches them)
DISTRACTOR_CLEARANCE_M = 0.065  # > the judge's 50 mm
ASIDE_CLEARANCE_M = 0.08  # a distractor put aside lands this far from both lines (a margin over the clearance)
MAX_VIEW_CHECKS = 400  # candidate layouts checked for slots the parked arm hides (best first)
DISTRACTOR_MOVE_COST = 100.0  # a layout's cost per distractor to move aside: more than every block in its way
SLOT_TOLERANCE_M = 0.012
BOARD_X_M = (-0.47, 0.47)  # slot centres stay this far inside the board's edges
BOARD_Y_M = (-0.15, 0.45)


def line_layouts(sizes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Candidate layouts as arrays: slots (L, lines, 6, 2) — slot k of a line holds rank k — and each
    layout's line direction (L,), over line centres on a grid across the reachable board and
    directions every 15° (both reading directions), the second line on either side of the first."""
    cx, cy, direction, side = np.meshgrid(np.arange(-0.25, 0.2501, 0.025), np.arange(-0.10, 0.3251, 0.025),
                                          np.radians(np.arange(0, 360, 15)), np.array([1.0, -1.0]), indexing="ij")
    cx, cy, direction, side = (a.ravel() for a in (cx, cy, direction, side))
    ux, uy = np.cos(direction), np.sin(direction)
    nx, ny = -uy * side, ux * side
    offsets = np.arange(6) - 2.5
    lines = np.arange(len(sizes))
    x = cx[:, None, None] + lines[None, :, None] * LINE_GAP_M * nx[:, None, None] + offsets * SPACING_M * ux[:, None, None]
    y = cy[:, None, None] + lines[None, :, None] * LINE_GAP_M * ny[:, None, None] + offsets * SPACING_M * uy[:, None, None]
    return np.stack([x, y], axis=-1), direction


def segment_distances(points: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Distance (L, P) from each of P points to each of L segments starts[l] → ends[l] (x-y)."""
    d = ends - starts  # (L, 2)
    rel = points[None, :, :] - starts[:, None, :]  # (L, P, 2)
    t = np.clip((rel @ d[:, :, None])[..., 0] / np.sum(d * d, axis=1)[:, None], 0.0, 1.0)
    return np.linalg.norm(rel - t[..., None] * d[:, None, :], axis=-1)


def choose_layout(runner: TaskRunner, objects: list[Seen], sizes: list[str]):
    """The layout with all slots in reach, on the board and off the tags, preferably with no distractor
    near (the judge's L3 bonus), else with the fewest distractors near (the rules allow moving them: the
    job puts them aside first; a held-out seed with four distractors left no layout clear and the job
    failed at t = 0), then the fewest blocks in its way (then the nearest the arm), with every slot in the camera's view
    while the arm is parked to look (in_view_first). Returns the layout
    ({size: six slots}), its direction and the distractors (detections) that must go aside."""
    slots, directions = line_layouts(sizes)
    flat = slots.reshape(len(slots), -1, 2)
    radius = np.linalg.norm(flat, axis=-1)
    ok = np.all((radius >= 0.14) & (radius <= 0.35), axis=1)
    ok &= np.all((flat[..., 0] > BOARD_X_M[0]) & (flat[..., 0] < BOARD_X_M[1]) & (flat[..., 1] > BOARD_Y_M[0])
                 & (flat[..., 1] < BOARD_Y_M[1]), axis=1)
    for tag in runner.tag_centres():
        ok &= np.all(np.linalg.norm(flat - np.asarray(tag), axis=-1) > 0.04, axis=1)
    if not ok.any():
        raise RuntimeError("no place for the lines in the arm's reach on the board")
    movable = [o for o in objects if not o.is_cube and not is_unseen(o)]
    distractors = np.array([o.position_m[:2] for o in movable]).reshape(-1, 2)
    blocks = [o for o in objects if o.is_cube]
    block_xy = np.array([o.position_m[:2] for o in blocks]).reshape(-1, 2)
    weights = np.array([o.stack_level for o in blocks], float)
    cost = 0.1 * radius.sum(axis=1)  # prefer lines near the arm (faster)
    near_line = np.zeros((len(slots), len(movable)), bool)
    for line in range(slots.shape[1]):
        starts, ends = slots[:, line, 0], slots[:, line, -1]
        if len(distractors):
            near_line |= segment_distances(distractors, starts, ends) < DISTRACTOR_CLEARANCE_M
        if len(block_xy):
            cost += ((segment_distances(block_xy, starts, ends) < CORRIDOR_M) * weights).sum(axis=1)
    cost += DISTRACTOR_MOVE_COST * near_line.sum(axis=1)
    best = in_view_first(runner, slots, np.flatnonzero(ok)[np.argsort(cost[ok], kind="stable")])
    layout = {size: [tuple(map(float, xy)) for xy in slots[best, j]] for j, size in enumerate(sizes)}
    return layout, float(directions[best]), [o for o, near in zip(movable, near_line[best]) if near]


def in_view_first(runner: TaskRunner, slots: np.ndarray, candidates: np.ndarray) -> int:
    """The first candidate layout (best first) whose every slot the arm, parked to look, leaves in the camera's
    view; else the best. A slot under the parked gripper reads, while empty, as something tall standing there
    (the depth sees the gripper): a held-out seed could not place its block beside one (220 of 500 points)."""
    hidden: dict[tuple[int, int], bool] = {}

    def seen(xy) -> bool:
        key = (round(float(xy[0]) * 200), round(float(xy[1]) * 200))  # 5 mm cells
        if key not in hidden:
            hidden[key] = skills.arm_hides_block(runner.station, runner.look_pose_rad, xy, runner.edges_m["large"])
        return not hidden[key]

    for index in candidates[:MAX_VIEW_CHECKS]:
        if all(seen(xy) for xy in slots[index].reshape(-1, 2)):
            return int(index)
    return int(candidates[0])


def segment_distance(p, a, b) -> float:
    return float(segment_distances(np.asarray([p[:2]], float), np.asarray([a], float), np.asarray([b], float))[0, 0])


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    sizes = ["large"] if level == 1 else ["large", "small"]
    chosen: dict = {}

    def policy(objects: list[Seen], given_up: set) -> Plan:
        if not chosen:
            layout, direction, to_move = choose_layout(runner, objects, sizes)
            if to_move:
                runner.station.events.add("info", f"line_up: no layout of the lines is clear of the distractors; "
                                          f"moving {len(to_move)} distractor(s) aside first")
            chosen.update(layout=layout, direction=direction)
            runner.reserved_m.extend(xy for line in layout.values() for xy in line)
        layout, direction = chosen["layout"], chosen["direction"]
        segments = [(line[0], line[-1]) for line in layout.values()]
        across = direction + math.pi / 2
        blocks = [b for b in cubes(objects) if b.size in sizes and b.color in COLORS]  # other colours: obstacles

        def slot_of(block):
            return layout[block.size][COLORS.index(block.color)]

        def placed(block) -> bool:
            return block.stack_level == 1 and near(block.position_m, slot_of(block), SLOT_TOLERANCE_M)

        done = [b for b in blocks if placed(b)]
        loose = [b for b in blocks if not placed(b)]
        left = sum(int(b.stack_level) for b in loose)
        moves: list[Move] = []

        def aside_key(obj) -> tuple:
            return Move(obj, (0.0, 0.0, 0.0), "").key()

        def in_the_way(obj) -> bool:
            """A block in the lines' corridor, or a distractor within DISTRACTOR_CLEARANCE_M of a line, that
            the job has not given up on (a given-up one stays: the lines are built around it)."""
            if obj in done or is_unseen(obj) or aside_key(obj) in given_up:
                return False
            reach_m = CORRIDOR_M if obj.is_cube else DISTRACTOR_CLEARANCE_M
            return any(segment_distance(obj.position_m[:2], a, b) < reach_m for a, b in segments)

        in_way = [o for o in objects if in_the_way(o)]

        def slot_free(xy) -> bool:
            return not any(near(o.position_m, xy, 0.035) for o in objects)

        def to_slot(block) -> Move:
            xy = slot_of(block)
            return Move(block, (xy[0], xy[1], 0.0), f"to slot {COLORS.index(block.color) + 1} of the "
                        f"{block.size} line", yaw_rad=direction, finger_axis_rad=across)

        def clear_of_lines(xy) -> bool:
            return all(segment_distance(xy, a, b) >= ASIDE_CLEARANCE_M for a, b in segments)

        def to_aside(obj) -> Move | None:
            """obj to a free spot the arm reaches and the parked arm leaves in view (a distractor: clear of
            the lines by ASIDE_CLEARANCE_M); None, said once, when there is none (the lines are built
            around it: a job does not fail for want of a free spot)."""
            cube = obj.is_cube
            try:
                x, y = runner.free_spot_in_reach(objects, runner.edge_of(obj), rules=(None if cube else clear_of_lines,))
            except NoFreeSpot as error:
                runner.note_once(f"left the {'block' if cube else 'distractor'} at ({obj.position_m[0] * 1000:.0f}, "
                                 f"{obj.position_m[1] * 1000:.0f}) mm in the lines' way: {error}")
                return None
            return Move(obj, (x, y, 0.0), "out of the lines' way", yaw_rad=0.0 if cube else None)

        # First clear the lines' corridor (to the block's own slot when it is free), then fill the
        # slots (pile tops first: they uncover others), then put aside pile tops that hide blocks.
        def clear_around(block) -> bool:
            """Nothing but placed blocks within an opening finger's reach of block's slot, not even the rest of
            its own pile (a release 47 mm from a two-high pile knocked it over: the blocks lay tipped)."""
            xy = slot_of(block)
            others = [o for o in objects if o not in done and (o is not block or o.stack_level > 1)]
            return not any(near(o.position_m, xy, FINGER_REACH_M) for o in others)

        for obj in sorted(in_way, key=lambda o: (o.is_cube, -(o.stack_level or 1))):  # distractors first
            wanted = obj in loose and slot_free(slot_of(obj)) and clear_around(obj)
            moves.append(to_slot(obj) if wanted else to_aside(obj))
        moves = [m for m in moves if m is not None]
        if not moves:
            for block in sorted(loose, key=lambda b: -b.stack_level):
                if slot_free(slot_of(block)):
                    moves.append(to_slot(block))
            for block in loose:
                if block.stack_level > 1:
                    moves.append(to_aside(block))
            moves = [m for m in moves if m is not None]
        distractors_left = [m for m in moves if not m.block.is_cube]
        return Plan(moves, done=len(done), left=left, finished=not loose and not distractors_left)

    return policy
