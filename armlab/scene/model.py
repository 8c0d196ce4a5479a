"""The scene data model: the objects on the board (type, colour, size, pose) and an optional to_the_sky
feeder, validated on construction, with their dict (ground-truth) form and the check that the simulation
can build a scene. Sizes come from the workcell config (armlab.workcell). The ground-truth dicts the
simulation serves have exactly the `SceneObject.to_dict()` format, so truth round-trips."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from armlab.errors import InvalidInput
from armlab.kinematics.rotations import quat_wxyz_from_yaw as quat_from_yaw
from armlab.kinematics.rotations import yaw_from_quat_wxyz as yaw_from_quat
from armlab.workcell import DEFAULT_WORKCELL, Workcell, load_workcell
from armlab.workcell.objects import DISTRACTOR_SHAPES

_ID_PATTERN = re.compile(r"[A-Za-z0-9_.:-]{1,64}")
OBJECT_TYPES = ("block", *DISTRACTOR_SHAPES)
DISTRACTOR_TYPES = DISTRACTOR_SHAPES
COLORS = ("red", "orange", "yellow", "green", "blue", "violet")  # rainbow order (DESIGN §7)
SIZES = ("large", "small")
FEED_ID_PREFIX = "feed_"  # feeder blocks are feed_0, feed_1, ... in the order they are fed


def as_workcell(workcell: Workcell | str | None) -> Workcell:
    """A Workcell from itself, its name, or None (the default workcell)."""
    return workcell if isinstance(workcell, Workcell) else load_workcell(workcell or DEFAULT_WORKCELL)


def workcell_name(workcell: Workcell | str | None) -> str:
    return workcell.name if isinstance(workcell, Workcell) else str(workcell or DEFAULT_WORKCELL)


def object_dimensions_m(obj_type: str, size: str | None, workcell: Workcell | str | None = None) -> tuple[float, float, float]:
    """(extent_x, extent_y, height) of an object in its body frame, metres (default workcell if None)."""
    return as_workcell(workcell).object_dimensions_m(obj_type, size)


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
