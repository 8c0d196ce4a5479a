"""to_the_sky (DESIGN §7): the tallest column of large blocks the arm can build, fed by the feeder.

One tower near the arm, where the camera sees all of it, clear of the park path and of the way to the
feed spot; the nearest loose large block goes on top, top-down. The job ends when no loose block is
left or the tower's top is out of top-down reach (six blocks for the RX200). Placing higher needs the
gripper horizontal (skills.plan_side_place), but a block picked top-down and set down that way lies on
its side, which §7 does not count as upright: that needs a side grasp from the board first (not yet)."""

from __future__ import annotations

import math

from armlab.tasks.columns import Column
from armlab.tasks.runner import Move, Plan, TaskRunner, cubes

TOWER_RADIUS_M = (0.13, 0.2)  # distance of the tower from the arm's base axis
MAX_TOWER_HEIGHT_M = 0.55
FEED_CLEARANCE_M = 0.15  # the tower stands this far from the feed spot, out of the way to it


def blocked_behind(xy, objects: list[dict]) -> int:
    """How many objects a tower at xy would stand in front of (seen from the arm's base, within 30°)."""
    bearing, radius = math.atan2(xy[1], xy[0]), math.hypot(*xy)
    return sum(1 for o in objects if math.hypot(*o["position_m"][:2]) > radius
               and abs(math.remainder(math.atan2(o["position_m"][1], o["position_m"][0]) - bearing, 2 * math.pi)) < math.radians(30))


def choose_base(runner: TaskRunner, objects: list[dict], feed_xy) -> tuple[float, float]:
    """A tower base in view up to MAX_TOWER_HEIGHT_M and clear of the park path; preferably clear of
    the feed spot and every object, then standing in front of as few objects as possible, then as far
    from every object as possible."""
    best, best_key = None, None
    for radius in (TOWER_RADIUS_M[0], sum(TOWER_RADIUS_M) / 2, TOWER_RADIUS_M[1]):
        for angle in range(-150, 151, 5):
            xy = (radius * math.sin(math.radians(angle)), radius * math.cos(math.radians(angle)))
            if not (runner.in_view(xy, MAX_TOWER_HEIGHT_M) and runner.clear_of_park(xy)):
                continue
            gap = min([math.dist(xy, o["position_m"][:2]) for o in objects] + [math.dist(xy, t) for t in runner.tag_centres()]
                      + [math.dist(xy, r) for r in runner.reserved_m], default=1.0)
            near_feed = feed_xy is not None and math.dist(xy, feed_xy) < FEED_CLEARANCE_M
            behind = blocked_behind(xy, objects) + (0 if feed_xy is None else blocked_behind(xy, [{"position_m": feed_xy}]) * 5)
            key = (gap <= 0.06 or near_feed, behind, -gap)  # crowded spots only when nothing else is in view
            if best_key is None or key < best_key:
                best, best_key = xy, key
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
            state["tower"] = Column("tower", choose_base(runner, objects, feed))
            runner.reserved_m.append(state["tower"].base_xy_m)
        tower: Column = state["tower"]
        tower.observe(objects, runner.height_at)
        loose = [b for b in cubes(objects) if b["size"] == "large" and not tower.holds(b)]
        base = tower.base_xy_m
        surface = tower.surface_m()
        if not runner.can_place_on(surface, runner.edges_m["large"]):
            runner.note_once(f"the tower stops at {tower.height} blocks: its top ({surface[2] * 1000:.0f} mm) is out of "
                             "the arm's top-down reach")
            return Plan([], done=tower.height, left=len(loose), finished=True)
        moves = [Move(block, surface, f"block {tower.height + 1} of the tower",
                      yaw_rad=tower.top["yaw_rad"] if tower.top is not None else 0.0,
                      on_placed=lambda edge, b=block: tower.add(b, edge))
                 for block in sorted(loose, key=lambda b: (b.get("stack_level", 1) == 1, math.dist(b["position_m"][:2], base)))]
        return Plan(moves, done=tower.height, left=len(loose), finished=not loose)

    return policy
