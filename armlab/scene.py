"""Scenes as data: the objects on the board (type, colour, size, pose), an optional to_the_sky feeder,
and seeded generators for every competition event and level of DESIGN §7, the sort_by_tag and
clear_table jobs, and random layouts. Sizes, board, tags, places, feed spot and bin come from the
workcell config (armlab.workcell). The simulation builds from a Scene; the ground-truth dicts it serves
have exactly the `SceneObject.to_dict()` format, so truth round-trips."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from armlab.errors import InvalidInput
from armlab.workcell import DEFAULT_SCENE_REACH_M, DEFAULT_WORKCELL, DISTRACTOR_SHAPES, Workcell, load_workcell

_ID_PATTERN = re.compile(r"[A-Za-z0-9_.:-]{1,64}")
OBJECT_TYPES = ("block", *DISTRACTOR_SHAPES)
DISTRACTOR_TYPES = DISTRACTOR_SHAPES
COLORS = ("red", "orange", "yellow", "green", "blue", "violet")  # rainbow order (DESIGN §7)
SIZES = ("large", "small")
FEED_ID_PREFIX = "feed_"  # feeder blocks are feed_0, feed_1, ... in the order they are fed

# Event name -> levels defined for it (DESIGN §7). Order matters: it seeds the generators.
EVENTS: dict[str, tuple[int, ...]] = {
    "pick_sort": (1, 2, 3),
    "pick_stack": (1, 2, 3),
    "line_up": (1, 2, 3),
    "stack_high": (1, 2),
    "to_the_sky": (1,),
    "sort_stack": (1, 2, 3),
}
# Every job with a scene generator: the judged events plus sort_by_tag and clear_table (not judged by §7).
JOBS: dict[str, tuple[int, ...]] = {**EVENTS, "sort_by_tag": (1, 2, 3), "clear_table": (1, 2, 3)}

# Generator choices (not workcell facts): the margin kept from the board edges (x, y), the tag keep-out and
# the gap between piles. Where a top-down grasp reaches comfortably (radius from the base axis) is the
# workcell's scene.reach_m (the RX200's 0.13-0.36 m by default).
REACH_MIN_M, REACH_MAX_M = DEFAULT_SCENE_REACH_M
BOARD_MARGIN_M = (0.02, 0.015)
TAG_KEEPOUT_M = 0.035
SPACING_MARGIN_M = 0.03  # free gap between footprints so fingers fit between neighbours


def as_workcell(workcell: Workcell | str | None) -> Workcell:
    """A Workcell from itself, its name, or None (the default workcell)."""
    return workcell if isinstance(workcell, Workcell) else load_workcell(workcell or DEFAULT_WORKCELL)


def workcell_name(workcell: Workcell | str | None) -> str:
    return workcell.name if isinstance(workcell, Workcell) else str(workcell or DEFAULT_WORKCELL)


def object_dimensions_m(obj_type: str, size: str | None, workcell: Workcell | str | None = None) -> tuple[float, float, float]:
    """(extent_x, extent_y, height) of an object in its body frame, metres (default workcell if None)."""
    return as_workcell(workcell).object_dimensions_m(obj_type, size)


def quat_from_yaw(yaw_rad: float) -> tuple[float, float, float, float]:
    """Quaternion (w, x, y, z) of a rotation by yaw_rad about world z."""
    return (math.cos(yaw_rad / 2.0), 0.0, 0.0, math.sin(yaw_rad / 2.0))


def yaw_from_quat(quat_wxyz) -> float:
    """Heading of the body x axis projected on the board, radians in (-pi, pi]."""
    w, x, y, z = (float(v) for v in quat_wxyz)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


WORKCELL_BOUND_M = 5.0  # |coordinate| of anything placed in a scene
MAX_SCENE_OBJECTS = 100  # 100 objects that only touch step fine (10 towers of 10: 0.6 s to build and settle)
BOARD_TOLERANCE_M = 0.001  # how far an object may reach under z = 0 (check_can_stand)


@dataclass(frozen=True)
class SceneObject:
    """One object: `position_m` is the body centre in the world (board) frame, `quat_wxyz` its orientation.

    size is "large"/"small" for blocks (required) and distractors (optional, None = large).
    aruco_id, if set, puts an ArUco tag (DICT_4X4_250) on the block's top face.
    workcell names the workcell config whose sizes it has (None = the default workcell); it is not part
    of the ground-truth dict (to_dict) nor of equality.
    """

    id: str
    type: str
    color: str
    size: str | None
    position_m: tuple[float, float, float]
    quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    aruco_id: int | None = None
    workcell: str | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not _ID_PATTERN.fullmatch(self.id):
            raise InvalidInput(f"SceneObject: id must be 1-64 letters, digits or _.:- characters, got {self.id!r}")
        if self.type not in OBJECT_TYPES:
            raise InvalidInput(f"SceneObject {self.id}: type {self.type!r} not one of {OBJECT_TYPES}")
        if self.color not in COLORS:
            raise InvalidInput(f"SceneObject {self.id}: color {self.color!r} not one of {COLORS}")
        if self.size not in (*SIZES, None) or (self.type == "block" and self.size is None):
            raise InvalidInput(f"SceneObject {self.id}: size {self.size!r} invalid (blocks need 'large' or 'small')")
        position = np.asarray(self.position_m, dtype=float)
        quat = np.asarray(self.quat_wxyz, dtype=float)
        if position.shape != (3,) or quat.shape != (4,):
            raise InvalidInput(f"SceneObject {self.id}: position_m needs 3 values and quat_wxyz 4")
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(quat))):
            raise InvalidInput(f"SceneObject {self.id}: position_m and quat_wxyz must be finite")
        if np.any(np.abs(position) > WORKCELL_BOUND_M):
            raise InvalidInput(f"SceneObject {self.id}: position_m {position.tolist()} is far outside the workcell")
        norm = float(np.linalg.norm(quat))
        if norm < 1e-6:
            raise InvalidInput(f"SceneObject {self.id}: quat_wxyz must be non-zero")
        if self.aruco_id is not None and (self.type != "block" or not 0 <= int(self.aruco_id) < 250):
            raise InvalidInput(f"SceneObject {self.id}: aruco_id needs a block and an id in 0..249")
        object.__setattr__(self, "position_m", tuple(float(v) for v in position))
        object.__setattr__(self, "quat_wxyz", tuple(float(v) for v in quat / norm))
        # Looked up once (the workcell config); not a dataclass field, so equality ignores it.
        object.__setattr__(self, "_dimensions_m", object_dimensions_m(self.type, self.size, self.workcell))

    @property
    def yaw_rad(self) -> float:
        return yaw_from_quat(self.quat_wxyz)

    @property
    def dimensions_m(self) -> tuple[float, float, float]:
        """(extent_x, extent_y, height) in the body frame, from the workcell config."""
        return self._dimensions_m

    @property
    def footprint_radius_m(self) -> float:
        """Radius of the circle that holds the footprint at any yaw."""
        extent_x, extent_y, _ = self.dimensions_m
        return 0.5 * math.hypot(extent_x, extent_y)

    def posed_dict(self, position_m, quat_wxyz) -> dict:
        """to_dict at a simulated pose. Not validated: a body pushed off the table falls on without end."""
        return {**self.to_dict(), "position_m": [float(x) for x in position_m], "yaw_rad": yaw_from_quat(quat_wxyz),
                "quat_wxyz": [float(x) for x in quat_wxyz]}

    def to_dict(self) -> dict:
        """The ground-truth object format (render CLI, sim-only API, scene files)."""
        data = {
            "id": self.id,
            "type": self.type,
            "color": self.color,
            "size": self.size,
            "position_m": list(self.position_m),
            "yaw_rad": self.yaw_rad,
            "quat_wxyz": list(self.quat_wxyz),
        }
        if self.aruco_id is not None:
            data["aruco_id"] = int(self.aruco_id)
        return data

    @classmethod
    def from_dict(cls, data: dict, workcell: str | None = None) -> SceneObject:
        """Accepts the ground-truth format; quat_wxyz wins over yaw_rad, which is used if it is alone.
        `workcell`: the workcell whose sizes the object has (None = the default)."""
        if not isinstance(data, dict):
            raise InvalidInput(f"scene object must be a mapping, got {type(data).__name__}")
        allowed = {"id", "type", "color", "size", "position_m", "yaw_rad", "quat_wxyz", "aruco_id"}
        unknown = set(data) - allowed
        if unknown:
            raise InvalidInput(f"scene object {data.get('id')!r}: unknown fields {sorted(unknown)}")
        missing = {"id", "type", "color", "position_m"} - set(data)
        if missing:
            raise InvalidInput(f"scene object {data.get('id')!r}: missing fields {sorted(missing)}")
        if data.get("quat_wxyz") is not None:
            quat = tuple(data["quat_wxyz"])
        else:
            yaw = float(data.get("yaw_rad", 0.0))
            if not math.isfinite(yaw):
                raise InvalidInput(f"scene object {data['id']!r}: yaw_rad must be finite")
            quat = quat_from_yaw(yaw)
        size = data.get("size", "large" if data["type"] == "block" else None)
        aruco = data.get("aruco_id")
        return cls(
            id=str(data["id"]),
            type=data["type"],
            color=data["color"],
            size=size,
            position_m=tuple(data["position_m"]),
            quat_wxyz=quat,
            aruco_id=None if aruco is None else int(aruco),
            workcell=workcell,
        )


@dataclass(frozen=True)
class Feeder:
    """to_the_sky's feeder: `count` large blocks in all, of which `fed` are already on the board (as
    scene objects feed_0 .. feed_<fed-1>); the simulation puts feed_<fed>, ... at spot_m (x, y) whenever
    the spot is clear. How "clear" is judged is the workcell's feeder config."""

    spot_m: tuple[float, float]
    count: int
    fed: int = 0

    def __post_init__(self) -> None:
        spot = np.asarray(self.spot_m, dtype=float)
        if spot.shape != (2,) or not np.all(np.isfinite(spot)) or np.any(np.abs(spot) > WORKCELL_BOUND_M):
            raise InvalidInput(f"Feeder: spot_m must be 2 finite values (x, y) in metres, got {self.spot_m!r}")
        if isinstance(self.count, bool) or not isinstance(self.count, int | np.integer) or not 0 <= self.count <= 100:
            raise InvalidInput(f"Feeder: count must be an integer in 0..100, got {self.count!r}")
        if isinstance(self.fed, bool) or not isinstance(self.fed, int | np.integer) or not 0 <= self.fed <= self.count:
            raise InvalidInput(f"Feeder: fed must be an integer in 0..count ({self.count}), got {self.fed!r}")
        object.__setattr__(self, "spot_m", (float(spot[0]), float(spot[1])))
        object.__setattr__(self, "count", int(self.count))
        object.__setattr__(self, "fed", int(self.fed))

    @property
    def remaining(self) -> int:
        return self.count - self.fed

    def block_id(self, index: int) -> str:
        return f"{FEED_ID_PREFIX}{index}"

    def waiting_ids(self) -> list[str]:
        """Ids of the blocks not yet fed, in feeding order."""
        return [self.block_id(i) for i in range(self.fed, self.count)]

    def to_dict(self) -> dict:
        return {"spot_m": list(self.spot_m), "count": self.count, "fed": self.fed, "remaining": self.remaining}

    @classmethod
    def from_dict(cls, data: dict) -> Feeder:
        """Accepts to_dict()'s format (remaining, if given, must equal count - fed)."""
        if not isinstance(data, dict):
            raise InvalidInput(f"feeder must be a mapping, got {type(data).__name__}")
        unknown = set(data) - {"spot_m", "count", "fed", "remaining"}
        if unknown or not {"spot_m", "count"} <= set(data):
            raise InvalidInput(f"feeder needs spot_m and count (optional fed, remaining), got fields {sorted(data)}")
        feeder = cls(spot_m=tuple(data["spot_m"]), count=data["count"], fed=data.get("fed", 0))
        if data.get("remaining") is not None and data["remaining"] != feeder.remaining:
            raise InvalidInput(f"feeder: remaining {data['remaining']!r} != count - fed = {feeder.remaining}")
        return feeder


@dataclass(frozen=True)
class Scene:
    """The objects on the board (ids unique) and, for to_the_sky, the feeder."""

    objects: tuple[SceneObject, ...] = field(default_factory=tuple)
    feeder: Feeder | None = None
    origin: tuple[str, int, int] | None = field(default=None, compare=False)  # (event, level, seed) of generate_scene
    workcell: str | None = field(default=None, compare=False)  # the workcell it was made for (None = the default)

    def __post_init__(self) -> None:
        objects = tuple(self.objects)
        ids = [obj.id for obj in objects]
        if len(set(ids)) != len(ids):
            raise InvalidInput(f"Scene: object ids must be unique, got {ids}")
        if self.feeder is not None:
            clash = sorted(set(ids) & set(self.feeder.waiting_ids()))
            if clash:
                raise InvalidInput(f"Scene: object ids {clash} are reserved for blocks the feeder has not fed yet")
        object.__setattr__(self, "objects", objects)

    def to_dict(self) -> dict:
        data = {"objects": [obj.to_dict() for obj in self.objects]}
        if self.feeder is not None:
            data["feeder"] = self.feeder.to_dict()
        return data

    @classmethod
    def from_dict(cls, data: dict, workcell: str | None = None) -> Scene:
        """From to_dict()'s format or a ground-truth dict (its other keys are ignored); `workcell` names the
        workcell whose sizes its objects have (None = the default)."""
        if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
            raise InvalidInput("scene must be a mapping with an 'objects' list")
        feeder = Feeder.from_dict(data["feeder"]) if data.get("feeder") is not None else None
        return cls(objects=tuple(SceneObject.from_dict(item, workcell) for item in data["objects"]), feeder=feeder,
                   workcell=workcell)

    def overlapping_pairs(self) -> list[tuple[str, str]]:
        """Pairs of objects whose bounding boxes intersect in 3-D (stacked objects only touch)."""
        pairs = []
        for i, first in enumerate(self.objects):
            for second in self.objects[i + 1 :]:
                if _boxes_overlap(first, second):
                    pairs.append((first.id, second.id))
        return pairs


def check_can_stand(scene: Scene) -> None:
    """ValueError naming the objects unless the simulation can build `scene`: at most MAX_SCENE_OBJECTS,
    none below the board (its lowest corner more than BOARD_TOLERANCE_M under z = 0) and no two
    overlapping (stacked objects only touch). MuJoCo pushes interpenetrating bodies apart violently: a
    block placed 1 m under the board flew to z = 98.8 m, and 100 blocks in one place exhausted its arena."""
    if len(scene.objects) > MAX_SCENE_OBJECTS:
        raise InvalidInput(f"a scene has at most {MAX_SCENE_OBJECTS} objects, this one {len(scene.objects)}")
    for obj in scene.objects:
        w, x, y, z = obj.quat_wxyz
        up = np.abs([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])  # world z row of R
        lowest_m = obj.position_m[2] - 0.5 * float(up @ np.asarray(obj.dimensions_m))
        if lowest_m < -BOARD_TOLERANCE_M:
            raise InvalidInput(f"scene object {obj.id} is below the board: its lowest point is at z = {lowest_m * 1000:.0f} mm")
    pairs = scene.overlapping_pairs()
    if pairs:
        shown = "; ".join(f"{a} and {b} overlap" for a, b in pairs[:5])
        more = f" (and {len(pairs) - 5} more pairs)" if len(pairs) > 5 else ""
        raise InvalidInput(f"scene objects may touch but not overlap: {shown}{more}")


def _boxes_overlap(first: SceneObject, second: SceneObject, tolerance_m: float = 1e-4) -> bool:
    """Conservative check with yaw-free bounding circles horizontally and heights vertically."""
    horizontal = math.dist(first.position_m[:2], second.position_m[:2])
    vertical = abs(first.position_m[2] - second.position_m[2])
    half_heights = 0.5 * (first.dimensions_m[2] + second.dimensions_m[2])
    if vertical >= half_heights - tolerance_m:
        return False
    # Same footprint centre = a stack (checked vertically above); otherwise circles must not intersect.
    return horizontal < first.footprint_radius_m + second.footprint_radius_m - tolerance_m


# ---------------------------------------------------------------------------------------------------
# Generators


@dataclass(frozen=True)
class _Region:
    """Where the bottom object of each footprint may be centred (also within reach and on the board,
    clear of the board tags and of the keep-out circles (x, y, radius) and rectangles (x0, x1, y0, y1))."""

    x_m: tuple[float, float]
    y_m: tuple[float, float]
    keepout_circles: tuple[tuple[float, float, float], ...] = ()
    keepout_rects: tuple[tuple[float, float, float, float], ...] = ()

    def contains(self, x: float, y: float, radius: float, workcell: Workcell) -> bool:
        r = math.hypot(x, y)
        reach_min_m, reach_max_m = workcell.scene.reach_m
        if not (reach_min_m <= r <= reach_max_m):
            return False
        if not (self.x_m[0] + radius <= x <= self.x_m[1] - radius and self.y_m[0] + radius <= y <= self.y_m[1] - radius):
            return False
        (bx0, bx1), (by0, by1) = workcell.board.x_range_m, workcell.board.y_range_m
        mx, my = BOARD_MARGIN_M
        if not (bx0 + mx + radius <= x <= bx1 - mx - radius and by0 + my + radius <= y <= by1 - my - radius):
            return False
        if any(math.dist((x, y), (cx, cy)) < cr + radius for cx, cy, cr in self.keepout_circles):
            return False
        if any(x0 - radius < x < x1 + radius and y0 - radius < y < y1 + radius for x0, x1, y0, y1 in self.keepout_rects):
            return False
        return all(math.dist((x, y), tag) >= TAG_KEEPOUT_M + radius for tag in workcell.board_tags.centres_m.values())


def _regions(workcell: Workcell) -> dict[str, _Region]:
    """The generators' regions: y > 0 (with a strip kept free), the tag rectangle, the whole board."""
    tag_x = [x for x, _ in workcell.board_tags.centres_m.values()]
    tag_y = [y for _, y in workcell.board_tags.centres_m.values()]
    board_x, board_y = workcell.board.x_range_m, workcell.board.y_range_m
    return {
        "positive_half": _Region(x_m=board_x, y_m=(0.04, board_y[1])),
        "tag_rectangle": _Region(x_m=(min(tag_x), max(tag_x)), y_m=(min(tag_y), max(tag_y))),
        "whole_board": _Region(x_m=board_x, y_m=board_y),
    }


def _stack_objects(
    pile: list[tuple[str, str | None, str]], x: float, y: float, yaw: float, first_index: int,
    aruco_ids: list[int | None] | None = None, workcell: Workcell | None = None,
) -> list[SceneObject]:
    """Objects of one footprint, bottom first (pile: (type, size, colour)); optional ArUco id per object."""
    workcell = as_workcell(workcell)
    objects = []
    z_bottom = 0.0
    for offset, (obj_type, size, color) in enumerate(pile):
        height = object_dimensions_m(obj_type, size, workcell)[2]
        prefix = "block" if obj_type == "block" else obj_type
        objects.append(
            SceneObject(
                id=f"{prefix}_{first_index + offset}",
                type=obj_type,
                color=color,
                size=size,
                position_m=(x, y, z_bottom + 0.5 * height),
                quat_wxyz=quat_from_yaw(yaw),
                aruco_id=aruco_ids[offset] if aruco_ids else None,
                workcell=workcell.name,
            )
        )
        z_bottom += height
    return objects


def _place_piles(piles: list[list[tuple]], region: _Region, rng: np.random.Generator,
                 workcell: Workcell | None = None, feeder: Feeder | None = None) -> Scene:
    """Place each pile (a stack of 1+ objects, bottom first) at a random reachable, non-overlapping spot.
    A pile item is (type, size, colour) or (type, size, colour, aruco_id)."""
    workcell = as_workcell(workcell)
    reach_max_m = workcell.scene.reach_m[1]
    for _attempt in range(50):
        placed: list[tuple[float, float, float]] = []  # x, y, footprint radius
        objects: list[SceneObject] = []
        ok = True
        for pile in piles:
            radius = max(0.5 * math.hypot(*object_dimensions_m(item[0], item[1], workcell)[:2]) for item in pile)
            for _try in range(400):
                x = rng.uniform(-reach_max_m, reach_max_m)
                y = rng.uniform(-reach_max_m, reach_max_m)
                if not region.contains(x, y, radius, workcell):
                    continue
                if all(math.dist((x, y), (px, py)) >= radius + pr + SPACING_MARGIN_M for px, py, pr in placed):
                    break
            else:
                ok = False
                break
            yaw = float(rng.uniform(-math.pi / 4.0, math.pi / 4.0))
            placed.append((x, y, radius))
            ids = [item[3] if len(item) > 3 else None for item in pile]
            objects.extend(_stack_objects([item[:3] for item in pile], x, y, yaw, len(objects), ids, workcell))
        if ok:
            return Scene(objects=tuple(objects), feeder=feeder, workcell=workcell.name)
    raise RuntimeError("could not place the scene's objects without overlap; ask for fewer objects")


def _blocks(sizes: list[str], colors: list[str]) -> list[tuple[str, str | None, str]]:
    return [("block", size, color) for size, color in zip(sizes, colors)]


def _into_piles(items: list, max_height: int, stack_probability: float, rng: np.random.Generator) -> list[list]:
    """Group items into piles of up to max_height (larger blocks at the bottom of each pile)."""
    order = list(rng.permutation(len(items)))
    piles: list[list] = []
    while order:
        height = 1
        while height < min(max_height, len(order)) and rng.random() < stack_probability:
            height += 1
        chosen = [items[i] for i in order[:height]]
        order = order[height:]
        chosen.sort(key=lambda item: 0 if item[1] in ("large", None) else 1)
        piles.append(chosen)
    return piles


def generate_scene(event: str, level: int = 1, seed: int = 0, workcell: Workcell | str | None = None) -> Scene:
    """A starting layout for a job and level on `workcell` (its board, tags, reach, places, block tags and
    sizes; None = the default workcell), reproducible from (event, level, seed, workcell): the competition
    events of DESIGN §7 (EVENTS) and the sort_by_tag and clear_table jobs (JOBS). The scene remembers
    (event, level, seed) as its origin (the page's scene picker shows it) and the workcell it is for."""
    cell = as_workcell(workcell)
    scene = _generate_scene(event, level, seed, cell)
    return Scene(scene.objects, scene.feeder, origin=(event, int(level), int(seed)), workcell=cell.name)


def _generate_scene(event: str, level: int, seed: int, workcell: Workcell) -> Scene:
    if event not in JOBS:
        raise InvalidInput(f"unknown event {event!r}; events: {', '.join(JOBS)}")
    if level not in JOBS[event]:
        raise InvalidInput(f"event {event!r} has levels {JOBS[event]}, not {level!r}")
    rng = np.random.default_rng([int(seed), list(JOBS).index(event), int(level)])
    regions = _regions(workcell)

    def random_colors(count: int) -> list[str]:
        return [str(c) for c in rng.choice(COLORS, size=count)]

    def distractors(count: int, sizes: bool = False) -> list[list[tuple]]:
        kinds = rng.choice(DISTRACTOR_TYPES, size=count)
        return [[(str(kind), str(rng.choice(SIZES)) if sizes else None, str(rng.choice(COLORS)))] for kind in kinds]

    def three_or_six_blocks(level: int, max_height: int) -> list[list[tuple]]:
        """§7's L1 (3 large R, G, B), L2 (3 large + 3 small, random colours), L3 (L2 piled up to max_height)."""
        if level == 1:
            return [[item] for item in _blocks(["large"] * 3, ["red", "green", "blue"])]
        items = _blocks(["large"] * 3 + ["small"] * 3, random_colors(6))
        return [[item] for item in items] if level == 2 else _into_piles(items, max_height, 0.35, rng)

    rainbow = list(COLORS)
    if event == "pick_sort":
        if level < 3:
            piles = three_or_six_blocks(level, 1)
        else:
            sizes = [str(s) for s in rng.choice(SIZES, size=9)]
            piles = _into_piles(_blocks(sizes, random_colors(9)), 2, 0.35, rng)
        return _place_piles(piles, regions["positive_half"], rng, workcell)
    if event == "pick_stack":
        return _place_piles(three_or_six_blocks(level, 2), regions["tag_rectangle"], rng, workcell)
    if event == "sort_stack":
        piles = three_or_six_blocks(level, 2) + (distractors(2) if level == 3 else [])
        return _place_piles(piles, regions["positive_half"], rng, workcell)
    if event == "line_up":
        items = _blocks(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = _into_piles(items + _blocks(["small"] * 6, rainbow), 4, 0.4, rng)
        if level == 3:
            kinds = rng.choice(DISTRACTOR_TYPES, size=int(rng.integers(2, 5)))
            piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in kinds]
        return _place_piles(piles, regions["whole_board"], rng, workcell)
    if event == "stack_high":
        items = _blocks(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = _into_piles(items, 4, 0.4, rng) + _into_piles(_blocks(["small"] * 6, rainbow), 4, 0.4, rng)
        return _place_piles(piles, regions["whole_board"], rng, workcell)
    if event == "to_the_sky":
        return _to_the_sky(rng, workcell, regions["whole_board"])
    if event == "sort_by_tag":
        return _sort_by_tag(level, rng, workcell, regions["positive_half"])
    return _clear_table(level, rng, workcell, regions["whole_board"], distractors)


def _to_the_sky(rng: np.random.Generator, workcell: Workcell, board: _Region) -> Scene:
    """Large blocks only, as many as the board takes comfortably, clear of the feed spot; plus the feeder."""
    spec = workcell.feeder
    feeder = Feeder(spot_m=spec.spot_m, count=spec.count)
    keepout = (*spec.spot_m, spec.clear_radius_m + SPACING_MARGIN_M)
    region = _Region(board.x_m, board.y_m, keepout_circles=(keepout,))
    items = _blocks(["large"] * 10, [COLORS[i % 6] for i in range(10)])
    return _place_piles([[item] for item in items], region, rng, workcell, feeder)


def _sort_by_tag(level: int, rng: np.random.Generator, workcell: Workcell, half: _Region) -> Scene:
    """Blocks with ArUco tops (id and colour from the workcell's block_tags), in y > 0, clear of the places.
    L1: one large block per id; L2: 6 blocks of random sizes and ids (ids repeat); L3: 8, piled up to 2 high."""
    tags = workcell.block_tags.ids
    if not tags:
        raise InvalidInput(f"sort_by_tag needs block_tags.ids in the workcell config {workcell.name!r}")
    ids = sorted(tags)
    if level == 1:
        chosen, sizes = ids, ["large"] * len(ids)
    else:
        count = 6 if level == 2 else 8
        chosen = [int(i) for i in rng.choice(ids, size=count)]
        sizes = [str(s) for s in rng.choice(SIZES, size=count)]
    items = [("block", size, tags[tag_id].color, tag_id) for size, tag_id in zip(sizes, chosen)]
    piles = [[item] for item in items] if level < 3 else _into_piles(items, 2, 0.35, rng)
    keepouts = tuple((x, y, 0.04) for x, y in workcell.places_m.values())
    region = _Region(half.x_m, half.y_m, keepout_circles=keepouts)
    return _place_piles(piles, region, rng, workcell)


def _clear_table(level: int, rng: np.random.Generator, workcell: Workcell, board: _Region, distractors) -> Scene:
    """Random blocks and distractors (any colour, shape and size) anywhere reachable outside the bin.
    L1: 3 blocks + 1 distractor; L2: 5 + 2; L3: 6 + 3, blocks piled up to 2 high."""
    n_blocks, n_distractors = {1: (3, 1), 2: (5, 2), 3: (6, 3)}[level]
    sizes = [str(s) for s in rng.choice(SIZES, size=n_blocks)]
    colors = [str(c) for c in rng.choice(COLORS, size=n_blocks)]
    items = _blocks(sizes, colors)
    piles = [[item] for item in items] if level < 3 else _into_piles(items, 2, 0.35, rng)
    piles += distractors(n_distractors, sizes=True)
    bin_ = workcell.bin
    region = _Region(board.x_m, board.y_m, keepout_rects=((*bin_.x_range_m, *bin_.y_range_m),))
    return _place_piles(piles, region, rng, workcell)


def aruco_ids_by_color(workcell: Workcell | None = None) -> dict[str, int]:
    """Colour -> ArUco id of the workcell's block tags (the first id of each colour)."""
    ids: dict[str, int] = {}
    for tag_id, entry in sorted(as_workcell(workcell).block_tags.ids.items()):
        ids.setdefault(entry.color, tag_id)
    return ids


def with_aruco_tops(scene: Scene, ids_by_color: dict[str, int] | None = None) -> Scene:
    """The same scene with an ArUco tag on the top face of every block whose colour has an id
    (default: the scene's workcell's block_tags, e.g. the UR3 write-up's yellow 100, red 150, blue 200)."""
    ids = aruco_ids_by_color(scene.workcell) if ids_by_color is None else ids_by_color
    return Scene(tuple(
        SceneObject(o.id, o.type, o.color, o.size, o.position_m, o.quat_wxyz,
                    ids.get(o.color) if o.type == "block" else None, workcell=o.workcell)
        for o in scene.objects
    ), feeder=scene.feeder, origin=scene.origin, workcell=scene.workcell)


def random_scene(
    seed: int = 0,
    n_blocks: int | None = None,
    n_distractors: int | None = None,
    max_stack: int = 1,
    aruco: bool = False,
    workcell: Workcell | str | None = None,
) -> Scene:
    """A random reachable layout on `workcell` (None = the default): n_blocks (default 3..10) blocks of
    random size and colour, n_distractors (default 0..2) distractors, stacks up to max_stack high;
    aruco=True puts the workcell's block tags on blocks of their colours (aruco_ids_by_color)."""
    if max_stack < 1:
        raise InvalidInput("max_stack must be >= 1")
    rng = np.random.default_rng([int(seed), 99])
    n_blocks = int(rng.integers(3, 11)) if n_blocks is None else int(n_blocks)
    n_distractors = int(rng.integers(0, 3)) if n_distractors is None else int(n_distractors)
    if not (0 <= n_blocks <= 16 and 0 <= n_distractors <= 6):
        raise InvalidInput("random_scene: n_blocks must be 0..16 and n_distractors 0..6")
    sizes = [str(s) for s in rng.choice(SIZES, size=n_blocks)]
    colors = [str(c) for c in rng.choice(COLORS, size=n_blocks)]
    piles = _into_piles(_blocks(sizes, colors), max_stack, 0.35, rng)
    piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in rng.choice(DISTRACTOR_TYPES, size=n_distractors)]
    workcell = as_workcell(workcell)
    scene = _place_piles(piles, _regions(workcell)["whole_board"], rng, workcell)
    return with_aruco_tops(scene) if aruco else scene
