"""to_the_sky (DESIGN §7): the tallest column of large blocks the arm can build, fed by the feeder.

One tower 0.21-0.25 m from the base axis, where the camera sees all of it, clear of the park path and
of the way to the feed spot. While the tower's top is in top-down reach (about six blocks for the
RX200) the loose large blocks go on top, top-down, those standing in the arm's way from the feed spot
first. Higher up the gripper must come in shallow; a block picked top-down and set down that way lies
on its side (not upright for §7), so there each block is picked and placed at one and the same pitch
with the fingers closing horizontally (skills.side_grasp): its tilt is place pitch − grasp pitch = 0.
Those grasps close across two faces only for a block whose yaw lines up with its bearing from the
base: the feeder's blocks do (the feed spot lies on the arm's +y axis and a fed block has yaw 0), and
blocks still in the arm's way are first set down in y < 0, turned to face the arm. Each block goes
straight above the tower's base at the depth-measured height (the job's own column memory), not on
the seen top's centre, which drifts with height. The job ends when no loose block is left or no pitch
reaches the top: 13 blocks (494 mm), the RX200's reach with the gripper level.

Tried before: top-down picks and a horizontal place (skills.plan_side_place) lay the block on its
side; the tower stopped at five blocks."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.skills import side_grasp
from armlab.tasks.columns import Column
from armlab.tasks.policy import Move, NoFreeSpot, Plan, cubes, near
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block

TOWER_RADIUS_M = (0.21, 0.25)  # distance of the tower from the arm's base axis
MAX_TOWER_HEIGHT_M = 0.55
TOWER_FOOTPRINT_M = 0.05  # detections this close to the tower's base (x-y) are the tower
FEED_CLEARANCE_M = 0.15  # the tower stands this far from the feed spot, out of the way to it
CORRIDOR_MARGIN_RAD = math.radians(20.0)
FEED_APPROACH_HALF_WIDTH_M = 0.10  # blocks this close to the way in to the feed spot (its inner half) are in the way
ASIDE_REGION_M = ((-0.30, 0.30), (-0.15, 0.0))  # where blocks in the way are put: the half the tower never uses


def blocked_behind(xy, points_m) -> int:
    """How many of the points (x, y, ...) a tower at xy would stand in front of (seen from the arm's base, within 30°)."""
    bearing, radius = math.atan2(xy[1], xy[0]), math.hypot(*xy)
    return sum(1 for p in points_m if math.hypot(*p[:2]) > radius
               and abs(math.remainder(math.atan2(p[1], p[0]) - bearing, 2 * math.pi)) < math.radians(30))


def choose_base(runner: TaskRunner, objects: list[Seen], feed_xy) -> tuple[float, float]:
    """A tower base in view up to MAX_TOWER_HEIGHT_M and clear of the park path; preferably clear of
    the feed spot and every object, then standing in front of as few objects as possible, then as far
    from every object as possible."""
    best, best_key = None, None
    for radius in (TOWER_RADIUS_M[0], sum(TOWER_RADIUS_M) / 2, TOWER_RADIUS_M[1]):
        for angle in range(-150, 151, 5):
            xy = (radius * math.sin(math.radians(angle)), radius * math.cos(math.radians(angle)))
            if not (runner.in_view(xy, MAX_TOWER_HEIGHT_M) and runner.clear_of_park(xy)):
                continue
            gap = min([math.dist(xy, o.position_m[:2]) for o in objects] + [math.dist(xy, t) for t in runner.tag_centres()]
                      + [math.dist(xy, r) for r in runner.reserved_m], default=1.0)
            near_feed = feed_xy is not None and math.dist(xy, feed_xy) < FEED_CLEARANCE_M
            behind = blocked_behind(xy, [o.position_m for o in objects]) + (0 if feed_xy is None else blocked_behind(xy, [feed_xy]) * 5)
            key = (gap <= 0.06 or near_feed, behind, -gap)  # crowded spots only when nothing else is in view
            if best_key is None or key < best_key:
                best, best_key = xy, key
    if best is None:
        raise RuntimeError("no spot for the tower that the camera sees whole")
    return best


def on_board(block: Block, edge_m: float) -> bool:
    """True if the detection stands on the board (its top one edge above it), not on another block."""
    return abs(block.position_m[2] - edge_m) < 0.008


@dataclass(frozen=True)
class LevelMove(Move):
    """A move onto the tower counted per tower level: the feeder puts blocks of the same colour on the
    same spot again and again, and the runner's attempt count (by colour and place) must not add up
    placements that succeeded at lower levels."""

    level: int = 0

    def key(self) -> tuple:
        return (*super().key(), self.level)


def side_moves(runner: TaskRunner, tower: Column, surface, loose: list[Block], feed_xy) -> list[Move]:
    """Moves putting a loose, aligned block on the tower at a pitch both ends reach (feed spot first)."""
    edge = runner.edges_m["large"]
    moves = []
    candidates = [b for b in loose if on_board(b, edge) and side_grasp.aligned(b)]
    anchor = feed_xy if feed_xy is not None else tower.base_xy_m
    for block in sorted(candidates, key=lambda b: math.dist(b.position_m[:2], anchor)):
        pitches = side_grasp.reachable_pitches(runner.station, block.position_m, surface, edge)
        if pitches:
            moves.append(LevelMove(block, surface, f"block {tower.height + 1} of the tower, picked and placed from the side",
                                   yaw_rad=None, grasp_pitches_rad=tuple(pitches), on_placed=lambda e, b=block: tower.add(b, e),
                                   level=tower.height + 1))
    return moves


def turn_moves(runner: TaskRunner, loose: list[Block], objects: list[Seen]) -> list[Move]:
    """Moves setting a loose block that is not aligned (or not on the board) down on a free spot,
    turned to face the arm, so a side grasp can take it next."""
    edge = runner.edges_m["large"]
    moves = []
    for block in loose:
        if on_board(block, edge) and side_grasp.aligned(block):
            continue
        try:
            spot = runner.free_spot([o for o in objects if o is not block], edge)
        except NoFreeSpot as error:  # the job goes on with its other moves
            runner.note_once(f"cannot turn the {block.color} block to face the arm: {error}")
            continue
        moves.append(Move(block, (spot[0], spot[1], 0.0), "turned to face the arm for a side grasp",
                          yaw_rad=side_grasp.bearing_rad(spot)))
    return moves


def in_the_way(block: Block, feed_xy, tower_xy) -> bool:
    """True if a block (not the one at the feed spot) stands where the arm sweeps carrying a block from
    the feed spot to the tower: between their bearings from the base (widened by CORRIDOR_MARGIN_RAD)."""
    xy = block.position_m[:2]
    if near(xy, feed_xy, 0.02) or math.hypot(*xy) < 0.06 or math.hypot(*xy) > max(math.hypot(*feed_xy), math.hypot(*tower_xy)) + 0.07:
        return False
    low, high = sorted((side_grasp.bearing_rad(feed_xy), side_grasp.bearing_rad(tower_xy)))
    bearing = side_grasp.bearing_rad(xy)
    # The gripper comes to the feed spot from the base side, its palm wide across the way.
    feed, point = np.asarray(feed_xy, float), np.asarray(xy, float)
    along = float(np.clip(np.dot(point - feed, -feed) / float(np.dot(feed, feed)), 0.0, 0.5))
    beside_approach = float(np.linalg.norm(point - feed * (1.0 - along))) < FEED_APPROACH_HALF_WIDTH_M
    return beside_approach or low - CORRIDOR_MARGIN_RAD <= bearing <= high + CORRIDOR_MARGIN_RAD


def aside_moves(runner: TaskRunner, blocking: list[Block], objects: list[Seen]) -> list[Move]:
    """Moves setting blocks that stand in the arm's way down on free spots in y < 0, out of it (turned to
    face the arm, so they can still be side-grasped later)."""
    edge = runner.edges_m["large"]
    moves, taken = [], []
    for block in blocking:
        try:
            spot = runner.free_spot([o for o in objects if o is not block], edge, region=ASIDE_REGION_M, avoid_m=taken)
        except NoFreeSpot:
            continue
        taken.append(spot)
        moves.append(Move(block, (spot[0], spot[1], 0.0), "moved out of the arm's way to the tower", yaw_rad=side_grasp.bearing_rad(spot)))
    return moves


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    state: dict = {}

    def policy(objects: list[Seen], given_up: set) -> Plan:
        feed = runner.feed_spot()
        if "tower" not in state:
            if feed is not None:
                runner.reserved_m.append(feed)
            state["tower"] = Column("tower", choose_base(runner, objects, feed))
            runner.reserved_m.append(state["tower"].base_xy_m)
        tower: Column = state["tower"]
        tower.observe(objects, runner.height_at)
        base = tower.base_xy_m
        # Whatever stands near the base is the tower (a tall one's top is seen up to a few cm off its
        # base): never a block to pick. Each block goes straight above the base at the measured height,
        # not on the seen top's centre, so the camera's error at height does not stair-step the tower.
        at_tower = [o for o in objects if near(o.position_m, base, TOWER_FOOTPRINT_M)]
        loose = [b for b in cubes(objects) if b.size == "large" and not any(b is o for o in at_tower)]
        surface = (float(base[0]), float(base[1]), float(tower.height_m if tower.height_m > 0.005 else 0.0))
        edge = runner.edges_m["large"]
        blocking = [b for b in loose if feed is not None and in_the_way(b, feed, base)]
        if runner.can_place_on(surface, edge):  # blocks in the arm's way from the feed spot go in first
            yaw = tower.top.yaw_rad if tower.top is not None else side_grasp.bearing_rad(base)
            order = sorted(loose, key=lambda b: (b.stack_level == 1, not any(b is o for o in blocking),
                                                 math.dist(b.position_m[:2], base)))
            moves = [LevelMove(block, surface, f"block {tower.height + 1} of the tower", yaw_rad=yaw,
                               on_placed=lambda edge, b=block: tower.add(b, edge), level=tower.height + 1) for block in order]
            return Plan(moves, done=tower.height, left=len(loose), finished=not loose)
        moves = aside_moves(runner, blocking, objects) + side_moves(runner, tower, surface, loose, feed)
        if not moves and feed is not None and side_grasp.reachable_pitches(runner.station, (*feed, edge), surface, edge):
            moves = turn_moves(runner, loose, objects)  # the top is in reach, but no loose block faces the arm
        if not moves:
            runner.note_once(f"the tower stops at {tower.height} blocks: no loose block can reach its top "
                             f"({surface[2] * 1000:.0f} mm) at a pitch it was picked at")
        return Plan(moves, done=tower.height, left=len(loose), finished=not moves)

    return policy
