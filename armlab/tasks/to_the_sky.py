"""to_the_sky (DESIGN §7): the tallest column of large blocks the arm can build, fed by the feeder.

One tower near the arm, where the camera sees all of it and the way to the park pose stays clear;
the nearest loose large block goes on top, top-down while the top is low enough, then with the
gripper horizontal beside the tower. The job ends when no loose block is left or the next block
cannot be placed any more."""

from __future__ import annotations

import math

from armlab.tasks.columns import Column
from armlab.tasks.runner import Move, Plan, TaskRunner, cubes

TOWER_RADIUS_M = (0.13, 0.2)  # distance of the tower from the arm's base axis
MAX_TOWER_HEIGHT_M = 0.55


def choose_base(runner: TaskRunner, objects: list[dict]) -> tuple[float, float]:
    """A tower base in view up to MAX_TOWER_HEIGHT_M, clear of the park path, far from every object."""
    best, best_gap = None, -1.0
    for radius in (TOWER_RADIUS_M[0], sum(TOWER_RADIUS_M) / 2, TOWER_RADIUS_M[1]):
        for angle in range(-150, 151, 5):
            xy = (radius * math.sin(math.radians(angle)), radius * math.cos(math.radians(angle)))
            if not (runner.in_view(xy, MAX_TOWER_HEIGHT_M) and runner.clear_of_park(xy)):
                continue
            gap = min([math.dist(xy, o["position_m"][:2]) for o in objects] + [math.dist(xy, t) for t in runner.tag_centres()]
                      + [math.dist(xy, r) for r in runner.reserved_m], default=1.0)
            if gap > best_gap:
                best, best_gap = xy, gap
    if best is None:
        raise RuntimeError("no spot for the tower that the camera sees whole")
    return best


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    state: dict = {}

    def policy(objects: list[dict], given_up: set) -> Plan:
        if "tower" not in state:
            feed = runner.feed_spot()
            if feed is not None:
                runner.reserved_m.append(feed)
            state["tower"] = Column("tower", choose_base(runner, objects))
            runner.reserved_m.append(state["tower"].base_xy_m)
        tower: Column = state["tower"]
        tower.observe(objects, runner.height_at)
        loose = [b for b in cubes(objects) if b["size"] == "large" and not tower.holds(b)]
        base = tower.base_xy_m
        moves = [Move(block, tower.surface_m(), f"block {tower.height + 1} of the tower",
                      yaw_rad=tower.top["yaw_rad"] if tower.top is not None else 0.0, side_ok=True,
                      on_placed=lambda edge, b=block: tower.add(b, edge))
                 for block in sorted(loose, key=lambda b: (b.get("stack_level", 1) == 1, math.dist(b["position_m"][:2], base)))]
        return Plan(moves, done=tower.height, left=len(loose), finished=not loose)

    return policy
