"""Scenes as data: the objects on the board (type, colour, size, pose) and seeded generators for every
competition event and level of DESIGN §7 plus random layouts. The simulation builds from a Scene; the
ground-truth dicts it serves have exactly the `SceneObject.to_dict()` format, so truth round-trips."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

_ID_PATTERN = re.compile(r"[A-Za-z0-9_.:-]{1,64}")
OBJECT_TYPES = ("block", "semicircle", "arch", "triangle", "cylinder")
DISTRACTOR_TYPES = ("semicircle", "arch", "triangle", "cylinder")
COLORS = ("red", "orange", "yellow", "green", "blue", "violet")
SIZES = ("large", "small")
BLOCK_EDGE_M = {"large": 0.038, "small": 0.025}

# Distractor dimensions (m): footprint extents along body x and y, and height. Body origin = centre of
# the footprint's bounding box at mid-height (the semicircle's flat side faces body -y).
DISTRACTOR_DIMENSIONS_M = {
    "semicircle": (0.050, 0.025, 0.025),
    "arch": (0.060, 0.025, 0.030),
    "triangle": (0.045, 0.039, 0.025),
    "cylinder": (0.038, 0.038, 0.038),
}

# Event name -> levels defined for it (DESIGN §7).
EVENTS: dict[str, tuple[int, ...]] = {
    "pick_sort": (1, 2, 3),
    "pick_stack": (1, 2, 3),
    "line_up": (1, 2, 3),
    "stack_high": (1, 2),
    "to_the_sky": (1,),
}

# Where a top-down grasp reaches comfortably (radius from the base axis, m), board limits, tag keep-out.
REACH_MIN_M = 0.13
REACH_MAX_M = 0.36
BOARD_X_M = (-0.48, 0.48)
BOARD_Y_M = (-0.16, 0.46)
TAG_CENTRES_M = ((-0.25, -0.025), (0.25, -0.025), (0.25, 0.275), (-0.25, 0.275))
TAG_KEEPOUT_M = 0.035
SPACING_MARGIN_M = 0.03  # free gap between footprints so fingers fit between neighbours


def object_dimensions_m(obj_type: str, size: str | None) -> tuple[float, float, float]:
    """(extent_x, extent_y, height) of an object in its body frame, metres."""
    if obj_type == "block":
        edge = BLOCK_EDGE_M[size or "large"]
        return (edge, edge, edge)
    scale = 1.0 if size in (None, "large") else 25.0 / 38.0
    return tuple(value * scale for value in DISTRACTOR_DIMENSIONS_M[obj_type])  # type: ignore[return-value]


def quat_from_yaw(yaw_rad: float) -> tuple[float, float, float, float]:
    """Quaternion (w, x, y, z) of a rotation by yaw_rad about world z."""
    return (math.cos(yaw_rad / 2.0), 0.0, 0.0, math.sin(yaw_rad / 2.0))


def yaw_from_quat(quat_wxyz) -> float:
    """Heading of the body x axis projected on the board, radians in (-pi, pi]."""
    w, x, y, z = (float(v) for v in quat_wxyz)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


@dataclass(frozen=True)
class SceneObject:
    """One object: `position_m` is the body centre in the world (board) frame, `quat_wxyz` its orientation.

    size is "large"/"small" for blocks (required) and distractors (optional, None = large).
    aruco_id, if set, puts an ArUco tag (DICT_4X4_250) on the block's top face.
    """

    id: str
    type: str
    color: str
    size: str | None
    position_m: tuple[float, float, float]
    quat_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    aruco_id: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not _ID_PATTERN.fullmatch(self.id):
            raise ValueError(f"SceneObject: id must be 1-64 letters, digits or _.:- characters, got {self.id!r}")
        if self.type not in OBJECT_TYPES:
            raise ValueError(f"SceneObject {self.id}: type {self.type!r} not one of {OBJECT_TYPES}")
        if self.color not in COLORS:
            raise ValueError(f"SceneObject {self.id}: color {self.color!r} not one of {COLORS}")
        if self.size not in (*SIZES, None) or (self.type == "block" and self.size is None):
            raise ValueError(f"SceneObject {self.id}: size {self.size!r} invalid (blocks need 'large' or 'small')")
        position = np.asarray(self.position_m, dtype=float)
        quat = np.asarray(self.quat_wxyz, dtype=float)
        if position.shape != (3,) or quat.shape != (4,):
            raise ValueError(f"SceneObject {self.id}: position_m needs 3 values and quat_wxyz 4")
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(quat))):
            raise ValueError(f"SceneObject {self.id}: position_m and quat_wxyz must be finite")
        if np.any(np.abs(position) > 5.0):
            raise ValueError(f"SceneObject {self.id}: position_m {position.tolist()} is far outside the workcell")
        norm = float(np.linalg.norm(quat))
        if norm < 1e-6:
            raise ValueError(f"SceneObject {self.id}: quat_wxyz must be non-zero")
        if self.aruco_id is not None and (self.type != "block" or not 0 <= int(self.aruco_id) < 250):
            raise ValueError(f"SceneObject {self.id}: aruco_id needs a block and an id in 0..249")
        object.__setattr__(self, "position_m", tuple(float(v) for v in position))
        object.__setattr__(self, "quat_wxyz", tuple(float(v) for v in quat / norm))

    @property
    def yaw_rad(self) -> float:
        return yaw_from_quat(self.quat_wxyz)

    @property
    def dimensions_m(self) -> tuple[float, float, float]:
        return object_dimensions_m(self.type, self.size)

    @property
    def footprint_radius_m(self) -> float:
        """Radius of the circle that holds the footprint at any yaw."""
        extent_x, extent_y, _ = self.dimensions_m
        return 0.5 * math.hypot(extent_x, extent_y)

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
    def from_dict(cls, data: dict) -> SceneObject:
        """Accepts the ground-truth format; quat_wxyz wins over yaw_rad, which is used if it is alone."""
        if not isinstance(data, dict):
            raise ValueError(f"scene object must be a mapping, got {type(data).__name__}")
        allowed = {"id", "type", "color", "size", "position_m", "yaw_rad", "quat_wxyz", "aruco_id"}
        unknown = set(data) - allowed
        if unknown:
            raise ValueError(f"scene object {data.get('id')!r}: unknown fields {sorted(unknown)}")
        missing = {"id", "type", "color", "position_m"} - set(data)
        if missing:
            raise ValueError(f"scene object {data.get('id')!r}: missing fields {sorted(missing)}")
        if data.get("quat_wxyz") is not None:
            quat = tuple(data["quat_wxyz"])
        else:
            yaw = float(data.get("yaw_rad", 0.0))
            if not math.isfinite(yaw):
                raise ValueError(f"scene object {data['id']!r}: yaw_rad must be finite")
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
        )


@dataclass(frozen=True)
class Scene:
    """The objects on the board; ids are unique."""

    objects: tuple[SceneObject, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        objects = tuple(self.objects)
        ids = [obj.id for obj in objects]
        if len(set(ids)) != len(ids):
            raise ValueError(f"Scene: object ids must be unique, got {ids}")
        object.__setattr__(self, "objects", objects)

    def to_dict(self) -> dict:
        return {"objects": [obj.to_dict() for obj in self.objects]}

    @classmethod
    def from_dict(cls, data: dict) -> Scene:
        if not isinstance(data, dict) or not isinstance(data.get("objects"), list):
            raise ValueError("scene must be a mapping with an 'objects' list")
        return cls(objects=tuple(SceneObject.from_dict(item) for item in data["objects"]))

    def overlapping_pairs(self) -> list[tuple[str, str]]:
        """Pairs of objects whose bounding boxes intersect in 3-D (stacked objects only touch)."""
        pairs = []
        for i, first in enumerate(self.objects):
            for second in self.objects[i + 1 :]:
                if _boxes_overlap(first, second):
                    pairs.append((first.id, second.id))
        return pairs


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
    """Where the bottom object of each footprint may be centred."""

    x_m: tuple[float, float]
    y_m: tuple[float, float]

    def contains(self, x: float, y: float, radius: float) -> bool:
        r = math.hypot(x, y)
        if not (REACH_MIN_M <= r <= REACH_MAX_M):
            return False
        if not (self.x_m[0] + radius <= x <= self.x_m[1] - radius and self.y_m[0] + radius <= y <= self.y_m[1] - radius):
            return False
        if not (BOARD_X_M[0] + radius <= x <= BOARD_X_M[1] - radius and BOARD_Y_M[0] + radius <= y <= BOARD_Y_M[1] - radius):
            return False
        return all(math.dist((x, y), tag) >= TAG_KEEPOUT_M + radius for tag in TAG_CENTRES_M)


POSITIVE_HALF = _Region(x_m=(-0.5, 0.5), y_m=(0.04, 0.475))
TAG_RECTANGLE = _Region(x_m=(-0.25, 0.25), y_m=(-0.025, 0.275))
WHOLE_BOARD = _Region(x_m=(-0.5, 0.5), y_m=(-0.175, 0.475))


def _stack_objects(
    pile: list[tuple[str, str | None, str]], x: float, y: float, yaw: float, first_index: int
) -> list[SceneObject]:
    """Objects of one footprint, bottom first (pile: (type, size, colour))."""
    objects = []
    z_bottom = 0.0
    for offset, (obj_type, size, color) in enumerate(pile):
        height = object_dimensions_m(obj_type, size)[2]
        prefix = "block" if obj_type == "block" else obj_type
        objects.append(
            SceneObject(
                id=f"{prefix}_{first_index + offset}",
                type=obj_type,
                color=color,
                size=size,
                position_m=(x, y, z_bottom + 0.5 * height),
                quat_wxyz=quat_from_yaw(yaw),
            )
        )
        z_bottom += height
    return objects


def _place_piles(
    piles: list[list[tuple[str, str | None, str]]], region: _Region, rng: np.random.Generator
) -> Scene:
    """Place each pile (a stack of 1+ objects) at a random reachable, non-overlapping spot."""
    for _attempt in range(50):
        placed: list[tuple[float, float, float]] = []  # x, y, footprint radius
        objects: list[SceneObject] = []
        ok = True
        for pile in piles:
            radius = max(0.5 * math.hypot(*object_dimensions_m(t, s)[:2]) for t, s, _ in pile)
            for _try in range(400):
                x = rng.uniform(-REACH_MAX_M, REACH_MAX_M)
                y = rng.uniform(-REACH_MAX_M, REACH_MAX_M)
                if not region.contains(x, y, radius):
                    continue
                if all(math.dist((x, y), (px, py)) >= radius + pr + SPACING_MARGIN_M for px, py, pr in placed):
                    break
            else:
                ok = False
                break
            yaw = float(rng.uniform(-math.pi / 4.0, math.pi / 4.0))
            placed.append((x, y, radius))
            objects.extend(_stack_objects(pile, x, y, yaw, len(objects)))
        if ok:
            return Scene(objects=tuple(objects))
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


def generate_scene(event: str, level: int = 1, seed: int = 0) -> Scene:
    """A starting layout for a competition event and level (DESIGN §7), reproducible from `seed`."""
    if event not in EVENTS:
        raise ValueError(f"unknown event {event!r}; events: {', '.join(EVENTS)}")
    if level not in EVENTS[event]:
        raise ValueError(f"event {event!r} has levels {EVENTS[event]}, not {level!r}")
    rng = np.random.default_rng([int(seed), list(EVENTS).index(event), int(level)])

    def random_colors(count: int) -> list[str]:
        return [str(c) for c in rng.choice(COLORS, size=count)]

    rainbow = list(COLORS)
    if event in ("pick_sort", "pick_stack"):
        region = POSITIVE_HALF if event == "pick_sort" else TAG_RECTANGLE
        if level == 1:
            items = _blocks(["large"] * 3, ["red", "green", "blue"])
            piles = [[item] for item in items]
        elif level == 2:
            items = _blocks(["large"] * 3 + ["small"] * 3, random_colors(6))
            piles = [[item] for item in items]
        else:
            sizes = [str(s) for s in rng.choice(SIZES, size=9)]
            piles = _into_piles(_blocks(sizes, random_colors(9)), 2, 0.35, rng)
        return _place_piles(piles, region, rng)
    if event == "line_up":
        items = _blocks(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = _into_piles(items + _blocks(["small"] * 6, rainbow), 4, 0.4, rng)
        if level == 3:
            kinds = rng.choice(DISTRACTOR_TYPES, size=int(rng.integers(2, 5)))
            piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in kinds]
        return _place_piles(piles, WHOLE_BOARD, rng)
    if event == "stack_high":
        items = _blocks(["large"] * 6, rainbow)
        if level == 1:
            piles = [[item] for item in items]
        else:
            piles = _into_piles(items, 4, 0.4, rng) + _into_piles(_blocks(["small"] * 6, rainbow), 4, 0.4, rng)
        return _place_piles(piles, WHOLE_BOARD, rng)
    # to_the_sky: large blocks only, as many as the board takes comfortably.
    items = _blocks(["large"] * 10, [rainbow[i % 6] for i in range(10)])
    return _place_piles([[item] for item in items], WHOLE_BOARD, rng)


# ArUco ids on block tops in the UR3 write-up (DESIGN §3): the colour -> destination mapping is config.
ARUCO_IDS_BY_COLOR = {"yellow": 100, "red": 150, "blue": 200}


def with_aruco_tops(scene: Scene, ids_by_color: dict[str, int] | None = None) -> Scene:
    """The same scene with an ArUco tag on the top face of every block whose colour has an id."""
    ids = ARUCO_IDS_BY_COLOR if ids_by_color is None else ids_by_color
    return Scene(tuple(
        SceneObject(o.id, o.type, o.color, o.size, o.position_m, o.quat_wxyz,
                    ids.get(o.color) if o.type == "block" else None)
        for o in scene.objects
    ))


def random_scene(
    seed: int = 0,
    n_blocks: int | None = None,
    n_distractors: int | None = None,
    max_stack: int = 1,
    aruco: bool = False,
) -> Scene:
    """A random reachable layout: n_blocks (default 3..10) blocks of random size and colour,
    n_distractors (default 0..2) distractors, stacks up to max_stack high; aruco=True puts the UR3
    write-up's tags on yellow, red and blue blocks (ARUCO_IDS_BY_COLOR)."""
    if max_stack < 1:
        raise ValueError("max_stack must be >= 1")
    rng = np.random.default_rng([int(seed), 99])
    n_blocks = int(rng.integers(3, 11)) if n_blocks is None else int(n_blocks)
    n_distractors = int(rng.integers(0, 3)) if n_distractors is None else int(n_distractors)
    if not (0 <= n_blocks <= 16 and 0 <= n_distractors <= 6):
        raise ValueError("random_scene: n_blocks must be 0..16 and n_distractors 0..6")
    sizes = [str(s) for s in rng.choice(SIZES, size=n_blocks)]
    colors = [str(c) for c in rng.choice(COLORS, size=n_blocks)]
    piles = _into_piles(_blocks(sizes, colors), max_stack, 0.35, rng)
    piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in rng.choice(DISTRACTOR_TYPES, size=n_distractors)]
    scene = _place_piles(piles, WHOLE_BOARD, rng)
    return with_aruco_tops(scene) if aruco else scene
