"""stack_high (DESIGN §7): one column per size holding all six blocks in rainbow order, red at the
bottom. Columns stand near the arm (tall columns are only reachable there). A column is in the way of
what stands close to it, a tall one also of what lies behind it (the stretched arm comes down over it)
and of what it hides from the camera: the bases are chosen, at the first look, where the full columns
will be in the way of as few blocks as possible (and not of each other), and the policy moves the rest
out of the way before a column grows over them (ordered_columns). Blocks the parked arm partly hides
are kept (runner.keep_occluded): every block must be found."""

from __future__ import annotations

import itertools
import math

import numpy as np

from armlab.tasks.ordered_columns import make_ordered_policy
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen

COLUMN_RADIUS_M = 0.17  # distance of a column from the arm's base axis
MIN_SEPARATION_M = 0.12
MAX_COLUMN_HEIGHT_M = 0.25  # six large blocks and a margin: the whole column must stay in the camera's view
BLOCKS_PER_COLUMN = 6  # ROYGBV
NEAR_M = 0.08  # a block this close to a column: the fingers and the held block pass within link clearance of it
TALL_M = 0.17  # a column this tall is in the way of the stretched arm reaching past it (the planner's maps):
BEHIND_M = 0.05  # ... to blocks this much farther from the base axis than the column ...
BEHIND_HALF_WIDTH_M = 0.065  # ... whose line from the base axis passes this close to it ...
FAR_RIM_M = 0.32  # ... and to blocks this far from the base axis (reached with the arm stretched low) ...
FAR_RIM_HALF_ANGLE_RAD = math.radians(25.0)  # ... within this angle of it (the arm swings over it)
CAMERA_SHADOW_HALF_WIDTH_M = 0.07  # half a large block + the block hidden + margin (a column leans a little)


def in_the_way(camera_xyz_m, base_xy_m, height_m: float, point_xy_m) -> bool:
    """True when a column of height_m at base_xy_m keeps the arm from a block at point_xy_m (close to it,
    behind it or on the far rim beyond it, once tall) or hides that block from the camera at camera_xyz_m."""
    base, point = np.asarray(base_xy_m, float), np.asarray(point_xy_m, float)
    if height_m <= 0.0:
        return False
    if np.linalg.norm(point - base) < NEAR_M:
        return True
    if height_m >= TALL_M:
        reach = float(np.linalg.norm(point))
        beside = abs(float(point[0] * base[1] - point[1] * base[0])) / reach  # the column's distance from the arm's line to the block
        if reach >= np.linalg.norm(base) + BEHIND_M and beside <= BEHIND_HALF_WIDTH_M and float(np.dot(point, base)) > 0.0:
            return True
        gap = math.atan2(point[0], point[1]) - math.atan2(base[0], base[1])
        if reach >= FAR_RIM_M and abs(math.remainder(gap, math.tau)) <= FAR_RIM_HALF_ANGLE_RAD:
            return True
    camera = np.asarray(camera_xyz_m, float)
    if camera[2] <= height_m + 1e-3:
        return True
    shadow = (base - camera[:2]) * height_m / (camera[2] - height_m)  # the top's far edge, projected onto the board
    length = float(np.linalg.norm(shadow))
    if length < 1e-6:
        return False
    along_dir = shadow / length
    along = float(np.dot(point - base, along_dir))
    across = abs(float(along_dir[0] * (point - base)[1] - along_dir[1] * (point - base)[0]))
    return -0.02 <= along <= length + 0.04 and across <= CAMERA_SHADOW_HALF_WIDTH_M


def way_of_columns(runner: TaskRunner):
    """in_the_way for the runner's camera: way(base_xy_m, height_m, point_xy_m) -> bool."""
    calibration = runner.station.calibration  # the camera's place decides what a column hides
    camera_xyz_m = np.asarray(calibration.T_world_camera, float)[:3, 3] if calibration is not None else (0.0, 0.0, 1e3)
    return lambda base_xy_m, height_m, point_xy_m: in_the_way(camera_xyz_m, base_xy_m, height_m, point_xy_m)


def choose_bases(runner: TaskRunner, objects: list[Seen], sizes: list[str]) -> dict[str, tuple[float, float]]:
    """A base per size on the circle of COLUMN_RADIUS_M: the pair whose full columns are in the way of
    the fewest blocks (and not of each other), then the one farthest from every object."""
    way = way_of_columns(runner)
    candidates = [(COLUMN_RADIUS_M * math.sin(a), COLUMN_RADIUS_M * math.cos(a))
                  for a in [math.radians(d) for d in range(-150, 151, 5)]]
    usable = [c for c in candidates if runner.in_view(c, MAX_COLUMN_HEIGHT_M) and runner.clear_of_park(c)]
    full_m = {size: BLOCKS_PER_COLUMN * runner.edges_m[size] for size in sizes}
    tags = runner.tag_centres()
    piles = [(o.position_m[:2], max(1, int(o.stack_level))) for o in objects]

    def blocked(size, xy) -> int:
        return sum(count for at, count in piles if way(xy, full_m[size], at))

    def clearance(xy) -> float:
        return min([math.dist(xy, at) for at, _ in piles] + [math.dist(xy, tag) for tag in tags], default=1.0)

    cost = {size: {c: blocked(size, c) for c in usable} for size in sizes}
    best, best_score = None, None
    for combo in itertools.permutations(usable, len(sizes)):
        if any(math.dist(a, b) < MIN_SEPARATION_M for a, b in itertools.combinations(combo, 2)):
            continue
        crossed = BLOCKS_PER_COLUMN * sum(way(a, full_m[sa], b) for (sa, a), (_, b) in itertools.permutations(zip(sizes, combo), 2))
        apart = min([0.5 * math.dist(a, b) for a, b in itertools.combinations(combo, 2)], default=1.0)
        score = (crossed + sum(cost[s][c] for s, c in zip(sizes, combo)), -min([clearance(c) for c in combo] + [apart]))
        if best_score is None or score < best_score:
            best, best_score = combo, score
    if best is None:  # depends on the arm and the camera only: nothing a move could free
        raise RuntimeError(f"no place for the columns: no {len(sizes)} spot(s) {MIN_SEPARATION_M * 1000:.0f} mm apart on the "
                           f"{COLUMN_RADIUS_M * 1000:.0f} mm circle that the camera sees whole and the parking arm passes")
    return dict(zip(sizes, best))


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    sizes = ["large"] if level == 1 else ["large", "small"]
    runner.keep_occluded = True  # every block must be found, also those the parked arm partly hides
    way = way_of_columns(runner)
    return make_ordered_policy(runner, None, choose_bases=lambda objects: choose_bases(runner, objects, sizes),
                               keep=lambda block: block.size in sizes,
                               in_the_way=lambda base, size, height_m, point: way(base, height_m, point))
