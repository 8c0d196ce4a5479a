"""The workcell (config/workcells/<name>.yaml): the arm (config/arms/<arm>.yaml) and its gripper type,
the arm's base pose on the board, the camera and its mount, board and grid, board tags, block and
distractor sizes, block-top ArUco ids, the spots the jobs use (sort_by_tag places, the to_the_sky
feeder, the clear_table bin) and the approach heights (overrides of config/motion.yaml). One fact, one place:
vision, scenes, the simulation, skills and the browser read it
from here (DESIGN §3). Validated at load; errors name the file and the field."""

from __future__ import annotations

import functools
import os
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from armlab.config import StrictModel, config_dir, load_config, read_config_file, resolve_config_path
from armlab.errors import ConfigError
from armlab.kinematics import load_arm
from armlab.kinematics.arm_model import ArmModel
from armlab.motion_config import MotionConfig, load_motion_config

DEFAULT_WORKCELL = "rx200_armlab"
_REPO_CONFIG_DIR = str(Path(__file__).resolve().parents[1] / "config")
DISTRACTOR_SHAPES = ("semicircle", "arch", "triangle", "cylinder")
BLOCK_SIZES = ("large", "small")

Positive = Annotated[float, Field(gt=0.0)]
Length = Annotated[float, Field(gt=0.0, lt=1.0)]  # an object or tag dimension, metres
Point2 = tuple[float, float]


def _ordered(name: str, bounds: tuple[float, float]) -> None:
    if not bounds[0] < bounds[1]:
        raise ValueError(f"{name}: lower bound {bounds[0]} must be below upper bound {bounds[1]}")


def _known_dictionary(name: str) -> str:
    import cv2

    if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
        raise ValueError(f"unknown OpenCV ArUco dictionary '{name}' (e.g. DICT_APRILTAG_36h11, DICT_4X4_250)")
    return name


def dictionary_size(name: str) -> int:
    """Number of markers in an OpenCV predefined dictionary or AprilTag family (ids are 0 .. size - 1)."""
    if name in APRILTAG_FAMILY_SIZES:
        return APRILTAG_FAMILY_SIZES[name]
    import cv2

    return int(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)).bytesList.shape[0])


# AprilTag families the AprilTag 3 library decodes, and their number of codes (ids 0 .. n - 1).
APRILTAG_FAMILY_SIZES = {"tag36h11": 587, "tagStandard41h12": 2115, "tag25h9": 35, "tag16h5": 30,
                         "tagCircle21h7": 38, "tagCircle49h12": 65535, "tagStandard52h13": 48714, "tagCustom48h12": 42211}


def is_apriltag_family(name: str) -> bool:
    """True for an AprilTag library family name (tag36h11, tagStandard41h12, ...), False for DICT_ names."""
    return name in APRILTAG_FAMILY_SIZES


def known_family(name: str) -> str:
    """The name if the AprilTag library (family) or OpenCV's ArUco module (DICT_...) decodes it."""
    if is_apriltag_family(name):
        return name
    try:
        return _known_dictionary(name)
    except ValueError:
        raise ValueError(f"unknown tag family '{name}': AprilTag families {sorted(APRILTAG_FAMILY_SIZES)} "
                         "or an OpenCV ArUco dictionary (DICT_APRILTAG_36h11, DICT_4X4_250, ...)") from None


class GridSpec(StrictModel):
    x_m: Point2
    y_m: Point2
    step_m: Length

    @model_validator(mode="after")
    def _check(self) -> GridSpec:
        _ordered("x_m", self.x_m)
        _ordered("y_m", self.y_m)
        return self


class BoardSpec(StrictModel):
    """The board rectangle (world x/y ranges, its surface at z = 0) and its grid points."""

    x_range_m: Point2
    y_range_m: Point2
    grid: GridSpec

    @model_validator(mode="after")
    def _check(self) -> BoardSpec:
        _ordered("x_range_m", self.x_range_m)
        _ordered("y_range_m", self.y_range_m)
        if not (self.x_range_m[1] - self.x_range_m[0] <= 4.0 and self.y_range_m[1] - self.y_range_m[0] <= 4.0):
            raise ValueError("board larger than 4 m: are the ranges in metres?")
        for axis, grid, board in (("x", self.grid.x_m, self.x_range_m), ("y", self.grid.y_m, self.y_range_m)):
            if grid[0] < board[0] - 1e-9 or grid[1] > board[1] + 1e-9:
                raise ValueError(f"grid.{axis}_m {list(grid)} reaches outside the board {list(board)}")
        return self

    def contains(self, x_m: float, y_m: float, margin_m: float = 0.0) -> bool:
        """True if (x, y) is on the board at least margin_m from every edge."""
        return (self.x_range_m[0] + margin_m <= x_m <= self.x_range_m[1] - margin_m
                and self.y_range_m[0] + margin_m <= y_m <= self.y_range_m[1] - margin_m)

    @property
    def corners_m(self) -> tuple[Point2, Point2, Point2, Point2]:
        """Corners counter-clockwise from (x_min, y_min)."""
        (x0, x1), (y0, y1) = self.x_range_m, self.y_range_m
        return ((x0, y0), (x1, y0), (x1, y1), (x0, y1))

    @property
    def size_m(self) -> Point2:
        return (self.x_range_m[1] - self.x_range_m[0], self.y_range_m[1] - self.y_range_m[0])

    def grid_points_m(self) -> np.ndarray:
        """The grid points (N, 3) at z = 0, row by row (y outer, x inner)."""
        step = self.grid.step_m
        xs = np.arange(self.grid.x_m[0], self.grid.x_m[1] + 1e-9, step)
        ys = np.arange(self.grid.y_m[0], self.grid.y_m[1] + 1e-9, step)
        gx, gy = np.meshgrid(xs, ys)
        return np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)


class BoardTagsSpec(StrictModel):
    """Calibration tags printed on the board: family, edge length (the side of the square a detector
    reports) and id -> centre (x, y) at z = 0. `dictionary` (optional): an OpenCV ArUco dictionary
    that decodes the family, used instead of the AprilTag library when set. Either inline in the
    workcell or the name of a config/boards/<name>.yaml file holding this mapping."""

    family: str
    dictionary: str | None = None
    size_m: Length
    centres_m: dict[int, Point2]

    @field_validator("family")
    @classmethod
    def _family_known(cls, name: str) -> str:
        return known_family(name)

    @field_validator("dictionary")
    @classmethod
    def _dictionary_known(cls, name: str | None) -> str | None:
        return None if name is None else _known_dictionary(name)

    @property
    def detector(self) -> str:
        """What decodes the tags: the OpenCV dictionary when one is set, else the family."""
        return self.dictionary or self.family

    @model_validator(mode="after")
    def _check(self) -> BoardTagsSpec:
        if len(self.centres_m) < 3:
            raise ValueError("centres_m needs at least 3 tags for a calibration")
        size = dictionary_size(self.detector)
        bad = [tag_id for tag_id in self.centres_m if not 0 <= tag_id < size]
        if bad:
            raise ValueError(f"centres_m: ids {bad} are not in {self.detector} (0..{size - 1})")
        return self


def board_file(name: str) -> dict:
    """The board_tags mapping of config/boards/<name>.yaml (ConfigError listing the boards if absent)."""
    data = read_config_file(resolve_config_path(name, "boards"))
    if not isinstance(data.get("board_tags"), dict):
        raise ValueError(f"config/boards/{name}.yaml has no board_tags mapping")
    return data["board_tags"]


class BlockSpec(StrictModel):
    edges_m: dict[str, Length]

    @model_validator(mode="after")
    def _check(self) -> BlockSpec:
        if set(self.edges_m) != set(BLOCK_SIZES):
            raise ValueError(f"edges_m must give exactly {list(BLOCK_SIZES)}, got {sorted(self.edges_m)}")
        if not self.edges_m["small"] < self.edges_m["large"]:
            raise ValueError("edges_m: small must be below large")
        return self


class ShapeSpec(StrictModel):
    extent_x_m: Length
    extent_y_m: Length
    height_m: Length


class DistractorSpec(StrictModel):
    """Distractor shapes (large version); small ones are scaled by small_scale (None = small/large block edge)."""

    small_scale: Annotated[float, Field(gt=0.0, le=1.0)] | None = None
    shapes: dict[str, ShapeSpec]

    @model_validator(mode="after")
    def _check(self) -> DistractorSpec:
        if set(self.shapes) != set(DISTRACTOR_SHAPES):
            raise ValueError(f"shapes must describe exactly {list(DISTRACTOR_SHAPES)}, got {sorted(self.shapes)}")
        return self


class BlockTagEntry(StrictModel):
    """What an ArUco id on a block's top face means: the block's colour and its sort_by_tag place."""

    color: str
    destination: int


class BlockTagsSpec(StrictModel):
    dictionary: str
    ids: dict[int, BlockTagEntry] = {}

    @field_validator("dictionary")
    @classmethod
    def _dictionary_known(cls, name: str) -> str:
        return _known_dictionary(name)

    @model_validator(mode="after")
    def _check(self) -> BlockTagsSpec:
        size = dictionary_size(self.dictionary)
        bad = [tag_id for tag_id in self.ids if not 0 <= tag_id < size]
        if bad:
            raise ValueError(f"ids {bad} are not in {self.dictionary} (0..{size - 1})")
        return self


class FeederSpec(StrictModel):
    """to_the_sky: where the simulated feeder puts new large blocks, how many it holds, when it is clear."""

    spot_m: Point2
    count: Annotated[int, Field(ge=0, le=100)]
    clear_radius_m: Length = 0.04
    arm_clearance_m: Annotated[float, Field(ge=0.0, lt=0.5)] = 0.02
    check_period_s: Annotated[float, Field(gt=0.0, le=5.0)] = 0.05


class BinSpec(StrictModel):
    """clear_table: the rectangle every object goes to."""

    x_range_m: Point2
    y_range_m: Point2

    @model_validator(mode="after")
    def _check(self) -> BinSpec:
        _ordered("x_range_m", self.x_range_m)
        _ordered("y_range_m", self.y_range_m)
        return self

    @property
    def centre_m(self) -> Point2:
        return (0.5 * sum(self.x_range_m), 0.5 * sum(self.y_range_m))

    def contains(self, x_m: float, y_m: float) -> bool:
        return self.x_range_m[0] <= x_m <= self.x_range_m[1] and self.y_range_m[0] <= y_m <= self.y_range_m[1]


GRIPPER_TYPES = ("fingers", "suction")


class GripperMarkerSpec(StrictModel):
    """A tag of the board's family fixed flat on the gripper, for finding the gripper in the camera
    (armlab.vision.gripper_marker): its id (not a board tag's), the detected square's edge, and its
    centre in the gripper-point frame (x along the approach, y along the fingers, z up when the
    gripper is level), as measured on the arm."""

    id: Annotated[int, Field(ge=0)]
    size_m: Length
    position_m: tuple[float, float, float]


class GripperChoice(StrictModel):
    """The end effector on the arm: `fingers` (a parallel gripper: the arm file's `gripper:` width range)
    or `suction` (a vacuum cup: the arm file's `suction_cup:`); marker: the tag on it, if any."""

    type: Literal["fingers", "suction"] = "fingers"
    marker: GripperMarkerSpec | None = None


class ArmBaseSpec(StrictModel):
    """The arm's base frame on the board: origin position_m (world), rotated yaw_deg about world z."""

    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: Annotated[float, Field(ge=-180.0, le=180.0)] = 0.0

    @property
    def T_world_base(self) -> np.ndarray:
        yaw = np.radians(self.yaw_deg)
        T = np.eye(4)
        T[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
        T[:3, 3] = self.position_m
        return T


class CameraMountSpec(StrictModel):
    """Nominal overhead camera mount (what software may assume before calibrating): camera centre in the
    world frame and tilt about the camera x axis toward -y. Overrides the camera file's `mount`."""

    position_m: tuple[float, float, float]
    tilt_deg: Annotated[float, Field(ge=0.0, le=45.0)]


class CameraSpec(StrictModel):
    """The overhead RGB-D camera: config/cameras/<name>.yaml, and this workcell's mount (None = the file's)."""

    name: str = "sim_l515"
    mount: CameraMountSpec | None = None


DEFAULT_SCENE_REACH_M = (0.13, 0.36)  # the RX200's comfortable top-down reach (radius from the base axis)


class SceneSpec(StrictModel):
    """Where the scene generators (armlab.scene) put objects: reach_m = (min, max) radius from the arm's
    base axis within which a top-down pick reaches comfortably."""

    reach_m: tuple[float, float] = DEFAULT_SCENE_REACH_M

    @model_validator(mode="after")
    def _check(self) -> SceneSpec:
        if not 0.0 <= self.reach_m[0] < self.reach_m[1] <= 5.0:
            raise ValueError(f"reach_m: need 0 <= min < max <= 5 m, got {list(self.reach_m)}")
        return self


class Workcell(StrictModel):
    """config/workcells/<name>.yaml, validated. World frame = board frame, metres (DESIGN §3)."""

    name: str
    arm: str = "rx200"                      # config/arms/<arm>.yaml
    gripper: GripperChoice = GripperChoice()
    arm_base: ArmBaseSpec | None = None     # None: the arm file's T_world_base
    camera: CameraSpec = CameraSpec()
    motion: dict[str, object] = {}          # overrides of config/motion.yaml (approach heights, workspace box)
    board: BoardSpec
    board_tags: BoardTagsSpec
    blocks: BlockSpec
    distractors: DistractorSpec
    block_tags: BlockTagsSpec
    places_m: dict[int, Point2] = {}
    feeder: FeederSpec
    bin: BinSpec
    scene: SceneSpec = SceneSpec()          # where the scene generators put objects
    # Where an autonomous job parks the arm while the camera looks (joints, rad): hides no block, place or
    # column from this workcell's camera. None = the arm file's sleep pose.
    look_pose_rad: tuple[float, ...] | None = None

    @field_validator("board_tags", mode="before")
    @classmethod
    def _board_by_name(cls, value):
        return board_file(value) if isinstance(value, str) else value

    @model_validator(mode="after")
    def _motion_overrides_valid(self) -> Workcell:
        if self.motion:
            try:
                MotionConfig.model_validate(self.motion)
            except Exception as error:  # pydantic ValidationError: name the field under motion
                raise ValueError(f"motion: {error}") from None
        return self

    @model_validator(mode="after")
    def _spots_on_the_board(self) -> Workcell:
        half_tag = 0.5 * self.board_tags.size_m
        for tag_id, (x, y) in self.board_tags.centres_m.items():
            if not self.board.contains(x, y, half_tag):
                raise ValueError(f"board_tags.centres_m.{tag_id}: ({x}, {y}) is not on the board")
        for place, (x, y) in self.places_m.items():
            if not self.board.contains(x, y):
                raise ValueError(f"places_m.{place}: ({x}, {y}) is not on the board")
        for tag_id, entry in self.block_tags.ids.items():
            if entry.destination not in self.places_m:
                raise ValueError(
                    f"block_tags.ids.{tag_id}.destination: place {entry.destination} is not in places_m {sorted(self.places_m)}"
                )
        marker = self.gripper.marker
        if marker is not None and (marker.id in self.board_tags.centres_m or marker.id >= dictionary_size(self.board_tags.detector)):
            raise ValueError(f"gripper.marker.id: {marker.id} is a board tag or not in {self.board_tags.detector}")
        overlap = set(self.board_tags.centres_m) & set(self.block_tags.ids)
        if overlap and self.board_tags.detector == self.block_tags.dictionary:
            raise ValueError(f"block_tags.ids: {sorted(overlap)} are also board tags of the same dictionary")
        if not self.board.contains(*self.feeder.spot_m, 0.5 * self.blocks.edges_m["large"]):
            raise ValueError(f"feeder.spot_m: {list(self.feeder.spot_m)} is not on the board")
        corners = [(x, y) for x in self.bin.x_range_m for y in self.bin.y_range_m]
        if not all(self.board.contains(x, y) for x, y in corners):
            raise ValueError("bin: the rectangle reaches outside the board")
        return self

    # ------------------------------------------------------------------ lookups
    def block_edge_m(self, size: str) -> float:
        """Edge of a cube of `size` ("large" or "small"), metres."""
        try:
            return float(self.blocks.edges_m[size])
        except KeyError:
            raise ValueError(f"block size must be one of {list(BLOCK_SIZES)}, got {size!r}") from None

    def object_dimensions_m(self, obj_type: str, size: str | None) -> tuple[float, float, float]:
        """(extent_x, extent_y, height) of a block or distractor in its body frame; size None = large."""
        if obj_type == "block":
            edge = self.block_edge_m(size or "large")
            return (edge, edge, edge)
        shape = self.distractors.shapes.get(obj_type)
        if shape is None:
            raise ValueError(f"unknown object type {obj_type!r}; distractors: {list(DISTRACTOR_SHAPES)}")
        if size not in (None, *BLOCK_SIZES):
            raise ValueError(f"size must be one of {list(BLOCK_SIZES)} or None, got {size!r}")
        small_scale = self.distractors.small_scale or self.block_edge_m("small") / self.block_edge_m("large")
        scale = 1.0 if size in (None, "large") else small_scale
        return (shape.extent_x_m * scale, shape.extent_y_m * scale, shape.height_m * scale)

    def board_tag_corners_m(self, tag_id: int) -> np.ndarray:
        """World corners (4, 3) of a board tag in OpenCV corner order (TL, TR, BR, BL seen from above, +y up)."""
        cx, cy = self.board_tags.centres_m[tag_id]
        h = self.board_tags.size_m / 2.0
        return np.array([[cx - h, cy + h, 0.0], [cx + h, cy + h, 0.0], [cx + h, cy - h, 0.0], [cx - h, cy - h, 0.0]])

    def place_m(self, destination: int) -> Point2:
        """Centre (x, y) of a sort_by_tag place."""
        if destination not in self.places_m:
            raise ValueError(f"no place {destination!r}; places: {sorted(self.places_m)}")
        return self.places_m[destination]

    def check_arm_fits(self) -> None:
        """ConfigError unless the arm file exists and carries what the gripper type needs (a finger width
        range for `fingers`, a suction cup for `suction`). Called when a station or simulation starts."""
        arm_file = resolve_config_path(self.arm, "arms")  # ConfigError listing the arms
        arm_data = read_config_file(arm_file)
        needs = {"fingers": ("gripper", "a finger width range (finger_offset_min_m, finger_offset_max_m)"),
                 "suction": ("suction_cup", "a suction cup (lip_radius_m, body_radius_m, body_length_m)")}
        section, what = needs[self.gripper.type]
        if not isinstance(arm_data.get(section), dict):
            raise ConfigError(
                f"workcell '{self.name}': gripper.type: '{self.gripper.type}' needs {what}, but {arm_file} has no "
                f"`{section}:` section (arm '{self.arm}'); choose the gripper the arm carries or add the section"
            )

    def T_world_base(self, arm_file_T_world_base) -> np.ndarray:
        """The arm's base pose on the board: arm_base if given, else the arm file's T_world_base."""
        if self.arm_base is None:
            return np.asarray(arm_file_T_world_base, dtype=float)
        return self.arm_base.T_world_base

    def to_wire(self) -> dict:
        """JSON-ready geometry for the browser (sent in the websocket hello)."""
        board = self.board
        return {
            "name": self.name,
            "arm": self.arm,
            "gripper_type": self.gripper.type,
            "board": {
                "x_range_m": list(board.x_range_m),
                "y_range_m": list(board.y_range_m),
                "grid": {"x_m": list(board.grid.x_m), "y_m": list(board.grid.y_m), "step_m": board.grid.step_m},
            },
            "board_tags": {
                "family": self.board_tags.family,
                "size_m": self.board_tags.size_m,
                "centres_m": {str(k): list(v) for k, v in self.board_tags.centres_m.items()},
            },
            "block_edges_m": dict(self.blocks.edges_m),
            "places_m": {str(k): list(v) for k, v in self.places_m.items()},
            "feeder_spot_m": list(self.feeder.spot_m),
            "bin": {"x_range_m": list(self.bin.x_range_m), "y_range_m": list(self.bin.y_range_m)},
        }


@functools.lru_cache(maxsize=8)
def _load_cached(path: str, _mtime_ns: int, _size: int) -> Workcell:
    return load_config(path, Workcell)


def load_workcell(name: str | Path = DEFAULT_WORKCELL) -> Workcell:
    """config/workcells/<name>.yaml (under $ARMLAB_CONFIG_DIR if set), or a .yaml/.json path.

    ConfigError naming the file and the field when invalid. The validated model is immutable and
    memoised per file version (path, mtime, size), so hot paths may call this freely."""
    if str(name).endswith((".yaml", ".yml", ".json")):
        path = str(name)
    else:  # config_dir() without its Path.resolve(): this runs per scene object
        path = f"{os.environ.get('ARMLAB_CONFIG_DIR') or _REPO_CONFIG_DIR}/workcells/{name}.yaml"
    try:
        stat = os.stat(path)
    except OSError:
        try:
            path = str(resolve_config_path(name, "workcells"))
        except ConfigError:
            folder = Path(os.environ.get("ARMLAB_CONFIG_DIR") or _REPO_CONFIG_DIR) / "workcells"
            raise ConfigError(f"unknown workcell '{name}': no config '{name}' in {folder} "
                              f"(available: {', '.join(known_workcells())})") from None
        stat = os.stat(path)
    return _load_cached(path, stat.st_mtime_ns, stat.st_size)


def known_workcells() -> list[str]:
    """Names of the workcell files in config/workcells/."""
    return sorted(path.stem for path in (config_dir() / "workcells").glob("*.yaml"))


def load_workcell_arm(workcell: Workcell | str | Path = DEFAULT_WORKCELL):
    """The workcell's arm model: load_arm(workcell.arm) with the base pose the workcell gives it."""
    cell = workcell if isinstance(workcell, Workcell) else load_workcell(workcell)
    cell.check_arm_fits()
    model = load_arm(cell.arm)
    if cell.arm_base is None:
        return model
    config = model.config.model_copy(update={"T_world_base": cell.arm_base.T_world_base.tolist()})
    return ArmModel(config, f"{model.name} in workcell {cell.name}")


def load_workcell_motion_config(workcell: Workcell | str | Path = DEFAULT_WORKCELL, path: str | Path | None = None):
    """config/motion.yaml (or `path`) with the workcell's `motion:` overrides applied (approach heights...)."""
    cell = workcell if isinstance(workcell, Workcell) else load_workcell(workcell)
    base = load_motion_config(path)
    if not cell.motion:
        return base
    return MotionConfig.model_validate({**base.model_dump(), **cell.motion})


def block_edge_m(size: str, workcell: Workcell | None = None) -> float:
    """Edge of a cube of `size` in `workcell` (default: the default workcell), metres."""
    return (workcell or load_workcell()).block_edge_m(size)
