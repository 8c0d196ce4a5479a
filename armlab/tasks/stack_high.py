"""stack_high (DESIGN §7): one column per size holding all six blocks in rainbow order, red at the
bottom. Columns stand near the arm (tall columns are only reachable there), at the free spots found
at the first look."""

from __future__ import annotations

import math

from armlab.tasks.ordered_columns import make_ordered_policy
from armlab.tasks.runner import TaskRunner, cubes

COLUMN_RADIUS_M = 0.17  # distance of a column from the arm's base axis
MIN_SEPARATION_M = 0.12
MAX_COLUMN_HEIGHT_M = 0.25  # six large blocks and a margin: the whole column must stay in the camera's view


def choose_bases(runner: TaskRunner, objects: list[dict], sizes: list[str]) -> dict[str, tuple[float, float]]:
    """A base per size on the circle of COLUMN_RADIUS_M, as far from every object as possible."""
    candidates = [(COLUMN_RADIUS_M * math.sin(a), COLUMN_RADIUS_M * math.cos(a))
                  for a in [math.radians(d) for d in range(-150, 151, 5)]]
    bases: dict[str, tuple[float, float]] = {}
    for size in sizes:
        def clearance(xy):
            gaps = [math.dist(xy, o["position_m"][:2]) for o in objects]
            gaps += [math.dist(xy, tag) for tag in runner.tag_centres()]
            gaps += [math.dist(xy, b) * 0.5 for b in bases.values()]  # keep the columns apart
            return min(gaps, default=1.0)

        usable = [c for c in candidates if all(math.dist(c, b) >= MIN_SEPARATION_M for b in bases.values())
                  and runner.in_view(c, MAX_COLUMN_HEIGHT_M) and runner.clear_of_park(c)]
        bases[size] = max(usable, key=clearance)
    return bases


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    sizes = ["large"] if level == 1 else ["large", "small"]
    return make_ordered_policy(runner, None, choose_bases=lambda objects: choose_bases(runner, objects, sizes),
                               keep=lambda block: block["size"] in sizes)
