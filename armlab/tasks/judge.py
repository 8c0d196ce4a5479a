"""The competition judge (DESIGN §7): points for a finished run from the final ground truth, the run's
simulated time and the gripper path. A pure function of those; perception never uses it.

Readings chosen where §7 leaves a choice (one line each):
- Thresholds are inclusive ("within 15°/30 mm" means <=), side tests strict (y < 0, x > 0), neatness strict (< 300 mm).
- Distances between centres are horizontal (xy); "on the board" and stacking use centre z -/+ edge/2 whatever the tilt.
- columns(): blocks only (a block on a distractor is in no column); blocks join lowest first, onto the nearest top.
- pick_sort / sort_stack sides: a block need not rest on the board; its centre decides (y < 0, then x by size).
- pick_stack: columns hold all blocks (any size, tipped ones too) and count them all; only upright blocks score.
- stack_high, to_the_sky, sort_stack: columns are built from upright blocks of one size, so a tipped or other-size block
  ends the column under it.
- line_up L1 and stack_high L1 score large blocks only (their max has no small line or column).
- line_up: a line's blocks are ordered by projection on the TLS direction (ties by id); the direction giving more
  points (neatness included) is used.
- line_up: a block that misses +30 gets +10 if within 60 mm of the line, whatever its colour.
- line_up neatness needs exactly six blocks in the line; its length is the xy distance between first and last centres.
- line_up L3: a line's segment spans its blocks' projections on the TLS line; a distractor's distance is from its
  centre (xy); the +100 needs both lines to hold at least one block.
- stack_high: +40 needs the column to be exactly red, orange, yellow, green, blue, violet bottom-up.
- sort_stack L2/L3: the side's single column is the tallest column of that size's upright blocks whose bottom block is
  on the side (equal heights: the one scoring more).
- sort_stack L2/L3: a block's expected position is 1 + the number of blocks of its size (all in truth) with a lower
  rainbow rank; blocks of equal colour may take their positions either way.
- Time: over the limit loses only the level bonus (pick_sort, pick_stack, sort_stack); other points stand, and the
  line_up / sort_stack distractor points are not a bonus. within_limit is sim_time_s <= limit.
- "Every block scoring" (bonus) is over all blocks in truth; pick_stack's bonus also needs a recorded gripper path,
  and an empty path (no samples after the first motion) never left the box.
- to_the_sky: blocks_available may not be below the number of large blocks in truth; other events refuse it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene import COLORS, Scene, SceneObject
from armlab.scene.events import EVENTS
from armlab.scene.model import WORKCELL_BOUND_M
from armlab.vision import load_perception_config

# Simulated seconds allowed per event (DESIGN §7).
EVENT_LIMITS_S: dict[str, float] = {
    "pick_sort": 180.0,
    "pick_stack": 120.0,
    "line_up": 600.0,
    "stack_high": 600.0,
    "to_the_sky": 600.0,
    "sort_stack": 180.0,
}
_SORT_STACK_LEVELS = (1, 2, 3)  # judged even before armlab.scene.EVENTS lists sort_stack

UPRIGHT_MAX_TILT_RAD = math.radians(15.0)
SURFACE_TOLERANCE_M = 0.006  # bottom face to the board, or to the top of the block below
STACK_XY_TOLERANCE_M = 0.015
TAG_RADIUS_M = 0.030  # pick_stack: bottom block centre to a tag centre
PICK_STACK_MIN_HEIGHT = 3
GRIPPER_BOX_M = {"x_abs_max": 0.260, "y_min": -0.035, "y_max": 0.285, "z_max": 0.300}
LINE_NEAR_M = 0.030
LINE_FAR_M = 0.060
NEAT_LENGTH_M = 0.300
DISTRACTOR_CLEARANCE_M = 0.050
RAINBOW = COLORS  # red, orange, yellow, green, blue, violet: rank 0..5
_LINE_UP_MAX = {1: 200, 2: 400, 3: 500}
_STACK_HIGH_MAX = {1: 250, 2: 500}


@dataclass(frozen=True)
class Rule:
    """One line of the breakdown: which rule gave how many points for which objects, and why."""

    rule: str
    points: int
    detail: str
    object_ids: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return {"rule": self.rule, "points": self.points, "detail": self.detail, "object_ids": list(self.object_ids)}


@dataclass(frozen=True)
class Score:
    """The judge's verdict; `full` = every point earned within the time limit."""

    points: int
    max_points: int
    within_limit: bool
    full: bool
    breakdown: tuple[Rule, ...]
    time_limit_s: float

    def to_dict(self) -> dict:
        return {
            "points": self.points,
            "max_points": self.max_points,
            "within_limit": self.within_limit,
            "full": self.full,
            "time_limit_s": self.time_limit_s,
            "breakdown": [rule.to_dict() for rule in self.breakdown],
        }


# ---------------------------------------------------------------------------------------------------
# Definitions used by every event


def _as_object(obj, workcell: str | None = None) -> SceneObject:
    """A SceneObject, or a truth dict read with `workcell`'s sizes (None = the default workcell)."""
    return obj if isinstance(obj, SceneObject) else SceneObject.from_dict(_within_bound(obj), workcell)


def _within_bound(data):
    """A truth object with its position clamped to the scene bound: a body pushed off the simulated table falls
    on without end, and is judged where it is, far off the board, not refused as a malformed scene."""
    if not isinstance(data, Mapping) or not isinstance(data.get("position_m"), (list, tuple)):
        return data
    bound = WORKCELL_BOUND_M - 1e-6
    position = [min(bound, max(-bound, x)) if isinstance(x, (int, float)) and math.isfinite(x) else x for x in data["position_m"]]
    return {**data, "position_m": position}


def tilt_rad(obj) -> float:
    """Angle between the object's body z axis and world z."""
    _w, x, y, _z = _as_object(obj).quat_wxyz
    return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))


def upright(obj) -> bool:
    """Body z axis within 15° of world z (a SceneObject or a truth dict)."""
    return tilt_rad(obj) <= UPRIGHT_MAX_TILT_RAD + 1e-12


def _bottom_z_m(obj: SceneObject) -> float:
    return obj.position_m[2] - 0.5 * obj.dimensions_m[2]


def _top_z_m(obj: SceneObject) -> float:
    return obj.position_m[2] + 0.5 * obj.dimensions_m[2]


def _xy(obj: SceneObject) -> np.ndarray:
    return np.array(obj.position_m[:2])


def on_board(obj) -> bool:
    """Bottom face (centre z - edge/2) within ±6 mm of the board surface z = 0."""
    return abs(_bottom_z_m(_as_object(obj))) <= SURFACE_TOLERANCE_M + 1e-12


def columns(objects, workcell: str | None = None) -> list[tuple[SceneObject, ...]]:
    """Stacks of the given blocks, each bottom first: a column starts with a block on the board, and a block joins
    the column whose top block's centre is within 15 mm (xy) and whose top is within ±6 mm of its bottom.
    Truth dicts are read with `workcell`'s block sizes (None = the default workcell)."""
    blocks = [obj for obj in (_as_object(o, workcell) for o in objects) if obj.type == "block"]
    stacks = [[block] for block in blocks if on_board(block)]
    rest = sorted((b for b in blocks if not on_board(b)), key=lambda b: (_bottom_z_m(b), b.id))
    for block in rest:
        best: tuple[float, list[SceneObject]] | None = None
        for stack in stacks:
            top = stack[-1]
            distance = float(np.linalg.norm(_xy(block) - _xy(top)))
            if distance <= STACK_XY_TOLERANCE_M and abs(_bottom_z_m(block) - _top_z_m(top)) <= SURFACE_TOLERANCE_M:
                if best is None or distance < best[0]:
                    best = (distance, stack)
        if best is not None:
            best[1].append(block)
    return [tuple(stack) for stack in stacks]


def tls_line(points) -> tuple[np.ndarray, np.ndarray]:
    """Total-least-squares line through points (N, 2) or (N, 3), xy used: (centroid (2,), unit direction (2,)).
    The direction's sign is canonical (x > 0, or y > 0 when vertical); callers read the line both ways."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[0] < 1 or pts.shape[1] not in (2, 3) or not np.all(np.isfinite(pts)):
        raise InvalidInput(f"tls_line needs (N, 2) or (N, 3) finite points with N >= 1, got shape {pts.shape}")
    xy = pts[:, :2]
    centre = xy.mean(axis=0)
    _u, _s, vt = np.linalg.svd(xy - centre)
    direction = vt[0] / np.linalg.norm(vt[0])
    if direction[0] < 0.0 or (direction[0] == 0.0 and direction[1] < 0.0):
        direction = -direction
    return centre, direction


def _line_distance_m(point: np.ndarray, centre: np.ndarray, direction: np.ndarray) -> float:
    offset = point - centre
    return abs(float(direction[0] * offset[1] - direction[1] * offset[0]))


def _segment_distance_m(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    span = end - start
    length_sq = float(span @ span)
    t = 0.0 if length_sq == 0.0 else min(1.0, max(0.0, float((point - start) @ span) / length_sq))
    return float(np.linalg.norm(point - (start + t * span)))


def tower_points(height: int) -> int:
    """to_the_sky: blocks 1-8 of the column score 30 each, 9 and up 50 each."""
    return 30 * min(height, 8) + 50 * max(height - 8, 0)


def board_tag_centres_m(workcell: str | None = None) -> tuple[tuple[float, float], ...]:
    """pick_stack's tag centres (x, y), from the board layout in configuration (`workcell`'s; None = the default)."""
    return tuple((float(x), float(y)) for x, y in load_perception_config(workcell=workcell).tags.board_tags.values())


# ---------------------------------------------------------------------------------------------------
# Input checks


def _check_event_level(event: str, level: int) -> float:
    if event not in EVENT_LIMITS_S:
        raise InvalidInput(f"judge: unknown event {event!r}; events: {', '.join(EVENT_LIMITS_S)}")
    levels = EVENTS.get(event, _SORT_STACK_LEVELS if event == "sort_stack" else ())
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level not in levels:
        raise InvalidInput(f"judge: event {event!r} has levels {tuple(levels)}, not {level!r}")
    return EVENT_LIMITS_S[event]


def _check_truth(truth, workcell: str | None = None) -> tuple[SceneObject, ...]:
    if not isinstance(truth, Mapping) or not isinstance(truth.get("objects"), list):
        raise InvalidInput("judge: truth must be a mapping with an 'objects' list (the SimWorkcell.truth() format)")
    try:
        return Scene.from_dict({"objects": [_within_bound(obj) for obj in truth["objects"]]}, workcell=workcell).objects
    except (ValueError, TypeError) as error:
        raise InvalidInput(f"judge: malformed truth object: {error}") from error


def _check_time(sim_time_s) -> float:
    try:
        value = float(sim_time_s)
    except (TypeError, ValueError):
        raise InvalidInput(f"judge: sim_time_s must be a number of seconds, got {sim_time_s!r}") from None
    if not math.isfinite(value) or value < 0.0:
        raise InvalidInput(f"judge: sim_time_s must be finite and >= 0, got {sim_time_s!r}")
    return value


def _check_path(gripper_path_m) -> np.ndarray | None:
    if gripper_path_m is None:
        return None
    try:
        path = np.asarray(gripper_path_m, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput("judge: gripper_path_m must be an (N, 3) sequence of positions in metres") from None
    if path.size == 0:
        return np.zeros((0, 3))
    if path.ndim != 2 or path.shape[1] != 3 or not np.all(np.isfinite(path)):
        raise InvalidInput(f"judge: gripper_path_m must be (N, 3) finite positions in metres, got shape {path.shape}")
    return path


def _check_tag_centres(tag_centres_m) -> np.ndarray:
    values = tag_centres_m.values() if isinstance(tag_centres_m, Mapping) else tag_centres_m
    try:
        centres = np.asarray(list(values), dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput("judge: tag_centres_m must be (x, y) pairs in metres") from None
    if centres.ndim != 2 or centres.shape[0] < 1 or centres.shape[1] != 2 or not np.all(np.isfinite(centres)):
        raise InvalidInput(f"judge: tag_centres_m must be one or more finite (x, y) pairs, got shape {centres.shape}")
    return centres


# ---------------------------------------------------------------------------------------------------
# Events


def _mm(value_m: float) -> str:
    return f"{1000.0 * value_m:.0f} mm"


def _on_its_side(block: SceneObject) -> bool:
    x, y, _ = block.position_m
    return y < 0.0 and (x < 0.0 if block.size == "small" else x > 0.0)


def _side_text(block: SceneObject) -> str:
    return f"{block.size} blocks go to y < 0, x {'<' if block.size == 'small' else '>'} 0"


def _tipped(block: SceneObject, rule: str) -> Rule:
    return Rule(rule, 0, f"tipped {math.degrees(tilt_rad(block)):.0f}° from vertical", (block.id,))


def _side_rule(block: SceneObject, rule: str, points: int) -> Rule:
    if not upright(block):
        return _tipped(block, rule)
    x, y, _ = block.position_m
    if not _on_its_side(block):
        return Rule(rule, 0, f"centre at ({_mm(x)}, {_mm(y)}): not on its side ({_side_text(block)})", (block.id,))
    return Rule(rule, points, f"upright on its side ({_side_text(block)})", (block.id,))


def _bonus_rule(points: int, within_limit: bool, limit_s: float, block_rules: list[Rule], *reasons: str) -> Rule:
    """The level bonus: needs the end within the limit, every block scoring, and no other reason against it."""
    missing = [rule.object_ids[0] for rule in block_rules if rule.points == 0]
    why = [reason for reason in reasons if reason]
    if not within_limit:
        why.append(f"over the {limit_s:.0f} s limit")
    if missing:
        why.append(f"{len(missing)} of {len(block_rules)} blocks not scoring")
    if why:
        return Rule("bonus", 0, "level bonus lost: " + "; ".join(why), tuple(missing))
    return Rule("bonus", points, "level bonus: every block scored within the time limit")


def _pick_sort(level, blocks, within_limit, limit_s):
    rules = [_side_rule(block, "sorted", 30) for block in blocks]
    return [*rules, _bonus_rule(10 * level, within_limit, limit_s, rules)], 30 * len(blocks) + 10 * level


def _gripper_left_box(path: np.ndarray | None) -> str:
    if path is None:
        return "gripper path not recorded, so staying inside the box is unproven"
    box = GRIPPER_BOX_M
    outside = ((np.abs(path[:, 0]) > box["x_abs_max"]) | (path[:, 1] < box["y_min"]) | (path[:, 1] > box["y_max"])
               | (path[:, 2] > box["z_max"]))
    if np.any(outside):
        x, y, z = path[int(np.argmax(outside))]
        return f"gripper left the box at ({_mm(x)}, {_mm(y)}, {_mm(z)})"
    return ""


def _pick_stack(level, blocks, within_limit, limit_s, path, tags):
    placement: dict[str, tuple[int, float]] = {}
    for stack in columns(blocks):
        tag_distance = float(np.min(np.linalg.norm(tags - _xy(stack[0]), axis=1)))
        for block in stack:
            placement[block.id] = (len(stack), tag_distance)
    rules = []
    for block in blocks:
        if not upright(block):
            rules.append(_tipped(block, "stacked"))
        elif block.id not in placement:
            rules.append(Rule("stacked", 0, "in no column (neither on the board nor on a column's top)", (block.id,)))
        elif placement[block.id][0] < PICK_STACK_MIN_HEIGHT:
            rules.append(Rule("stacked", 0, f"in a column of {placement[block.id][0]} (< 3)", (block.id,)))
        elif placement[block.id][1] > TAG_RADIUS_M:
            rules.append(Rule("stacked", 0, f"column's bottom is {_mm(placement[block.id][1])} from the nearest tag "
                                            f"centre (> 30 mm)", (block.id,)))
        else:
            rules.append(Rule("stacked", 40, f"upright in a column of {placement[block.id][0]} on a tag", (block.id,)))
    bonus = _bonus_rule(20 * level, within_limit, limit_s, rules, _gripper_left_box(path))
    return [*rules, bonus], 40 * len(blocks) + 20 * level


def _score_line(order: list[SceneObject], centre, direction) -> list[Rule]:
    rules = []
    for k, block in enumerate(order):
        distance = _line_distance_m(_xy(block), centre, direction)
        if RAINBOW.index(block.color) == k and distance <= LINE_NEAR_M:
            rules.append(Rule("line", 30, f"place {k + 1}, right colour, {_mm(distance)} from the line", (block.id,)))
        elif distance <= LINE_FAR_M:
            rules.append(Rule("line", 10, f"place {k + 1} ({block.color}), {_mm(distance)} from the line",
                              (block.id,)))
        else:
            rules.append(Rule("line", 0, f"place {k + 1} ({block.color}), {_mm(distance)} from the line (> 60 mm)",
                              (block.id,)))
    ids = tuple(block.id for block in order)
    if len(order) != 6 or any(rule.points != 30 for rule in rules):
        rules.append(Rule("neatness", 0, "needs six blocks in rainbow order, each within 30 mm", ids))
    else:
        length = float(np.linalg.norm(_xy(order[-1]) - _xy(order[0])))
        points = 20 if length < NEAT_LENGTH_M else 0
        rules.append(Rule("neatness", points, f"first to last centre {_mm(length)} (needs < 300 mm)", ids))
    return rules


def _line_up(level, objects, blocks):
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
            order = sorted(members, key=lambda b: (float((_xy(b) - centre) @ direction), b.id))
            candidate = _score_line(order, centre, direction)
            if best is None or sum(r.points for r in candidate) > sum(r.points for r in best):
                best = candidate
        rules.extend(best)
        along = [float((_xy(b) - centre) @ axis) for b in members]
        segments.append((centre + min(along) * axis, centre + max(along) * axis))
    if level == 3:
        distractors = [obj for obj in objects if obj.type != "block"]
        ids = tuple(obj.id for obj in distractors)
        if len(segments) < len(sizes):
            rules.append(Rule("distractors", 0, "needs both lines to exist", ids))
        else:
            near = [(min(_segment_distance_m(_xy(obj), a, b) for a, b in segments), obj.id) for obj in distractors]
            close = sorted(item for item in near if item[0] < DISTRACTOR_CLEARANCE_M)
            if close:
                rules.append(Rule("distractors", 0, f"{close[0][1]} is {_mm(close[0][0])} from a line (< 50 mm)",
                                  tuple(obj_id for _, obj_id in close)))
            else:
                rules.append(Rule("distractors", 100, "every distractor is >= 50 mm from both lines", ids))
    return rules, _LINE_UP_MAX[level]


def _stack_high(level, blocks):
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


def _to_the_sky(blocks, blocks_available):
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


def _sort_stack(level, objects, blocks, within_limit, limit_s):
    if level == 1:
        rules = [_side_rule(block, "sorted", 30) for block in blocks]
    else:
        rules = []
        for size in ("large", "small"):
            rules.extend(_sorted_column_rules([b for b in blocks if b.size == size]))
        order = {block.id: i for i, block in enumerate(blocks)}
        rules.sort(key=lambda rule: order[rule.object_ids[0]])
    extra = [_bonus_rule(10 * level, within_limit, limit_s, rules)]
    if level == 3:
        strays = tuple(obj.id for obj in objects if obj.type != "block" and obj.position_m[1] < 0.0)
        extra.append(Rule("distractors", 0 if strays else 90,
                          "distractors with centre at y < 0" if strays else "no distractor's centre at y < 0", strays))
    return [*rules, *extra], 30 * len(blocks) + 10 * level + (90 if level == 3 else 0)


def _sorted_column_rules(of_size: list[SceneObject]) -> list[Rule]:
    """sort_stack L2/L3 for one size: on its side and at its rainbow position in the side's single column."""
    ranks = [RAINBOW.index(b.color) for b in of_size]
    allowed = {b.id: (sum(r < rank for r in ranks) + 1, sum(r <= rank for r in ranks))
               for b, rank in zip(of_size, ranks)}

    def placed(stack) -> int:
        return sum(allowed[b.id][0] <= n <= allowed[b.id][1] and _on_its_side(b) for n, b in enumerate(stack, 1))

    side = [s for s in columns([b for b in of_size if upright(b)]) if _on_its_side(s[0])]
    chosen = max(side, key=lambda s: (len(s), placed(s))) if side else ()
    position = {b.id: n for n, b in enumerate(chosen, 1)}
    rules = []
    for block in of_size:
        first, last = allowed[block.id]
        wanted = f"position {first}" if first == last else f"position {first}-{last}"
        if not upright(block) or not _on_its_side(block):
            rules.append(_side_rule(block, "sorted", 0))
        elif block.id not in position:
            rules.append(Rule("sorted", 0, "on its side but not in the side's column", (block.id,)))
        elif not first <= position[block.id] <= last:
            rules.append(Rule("sorted", 0, f"at position {position[block.id]} of the side's column; rainbow order "
                                           f"wants {wanted}", (block.id,)))
        else:
            rules.append(Rule("sorted", 30, f"on its side at {wanted} of the side's column", (block.id,)))
    return rules


# ---------------------------------------------------------------------------------------------------


def judge(
    event: str,
    level: int,
    truth: dict,
    *,
    sim_time_s: float,
    gripper_path_m=None,
    blocks_available: int | None = None,
    tag_centres_m=None,
    workcell: str | None = None,
) -> Score:
    """Score a finished run of `event` at `level` from the final ground truth (DESIGN §7).

    sim_time_s: simulated seconds from the job's start to its end. gripper_path_m: (N, 3) gripper-point positions
    from the end of the job's first motion to the end (pick_stack's bonus; None = not recorded, bonus not earned).
    blocks_available: to_the_sky's block count (board + feeder; default the large blocks in truth).
    tag_centres_m: pick_stack's tag centres, (x, y) pairs or {id: (x, y)}; None = from configuration.
    workcell: the workcell run on (its block sizes and board tags; None = the default).
    Raises ValueError for an unknown event or level, malformed truth, or bad arguments.
    """
    limit_s = _check_event_level(event, level)
    time_s = _check_time(sim_time_s)
    objects = _check_truth(truth, workcell)
    path = _check_path(gripper_path_m)
    if blocks_available is not None and event != "to_the_sky":
        raise InvalidInput(f"judge: blocks_available applies to to_the_sky only, not {event!r}")
    if tag_centres_m is not None:
        tags = _check_tag_centres(tag_centres_m)
    elif event == "pick_stack":
        tags = _check_tag_centres(board_tag_centres_m(workcell))
    level = int(level)
    within_limit = time_s <= limit_s
    blocks = [obj for obj in objects if obj.type == "block"]
    if event == "pick_sort":
        rules, max_points = _pick_sort(level, blocks, within_limit, limit_s)
    elif event == "pick_stack":
        rules, max_points = _pick_stack(level, blocks, within_limit, limit_s, path, tags)
    elif event == "line_up":
        rules, max_points = _line_up(level, objects, blocks)
    elif event == "stack_high":
        rules, max_points = _stack_high(level, blocks)
    elif event == "to_the_sky":
        rules, max_points = _to_the_sky(blocks, blocks_available)
    else:
        rules, max_points = _sort_stack(level, objects, blocks, within_limit, limit_s)
    points = sum(rule.points for rule in rules)
    return Score(points, int(max_points), within_limit, points == max_points and within_limit, tuple(rules), limit_s)
