"""The workcell model (config/workcells/<name>.yaml): the arm (config/arms/<arm>.yaml) and its gripper type,
the arm's base pose on the board, the camera and its mount, board and grid, board tags, block and
distractor sizes, block-top ArUco ids, the spots the jobs use (sort_by_tag places, the to_the_sky
feeder, the clear_table bin) and the approach heights (overrides of config/motion.yaml). One fact, one place:
vision, scenes, the simulation, skills and the browser read it
from here (DESIGN §3). Validated at load; errors name the file and the field."""

from __future__ import annotations

import numpy as np
from pydantic import field_validator, model_validator

from armlab.config import StrictModel, read_config_file, resolve_config_path
from armlab.errors import ConfigError, InvalidInput
from armlab.motion_config import MotionConfig
from armlab.workcell.board import BoardSpec, BoardTagsSpec, board_file
from armlab.workcell.fields import Point2
from armlab.workcell.objects import BLOCK_SIZES, DISTRACTOR_SHAPES, BlockSpec, BlockTagsSpec, DistractorSpec
from armlab.workcell.rig import ArmBaseSpec, CameraSpec, GripperChoice
from armlab.workcell.spots import BinSpec, FeederSpec, SceneSpec
from armlab.workcell.tag_families import dictionary_size


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
                raise InvalidInput(f"motion: {error}") from None
        return self

    @model_validator(mode="after")
    def _spots_on_the_board(self) -> Workcell:
        half_tag = 0.5 * self.board_tags.size_m
        for tag_id, (x, y) in self.board_tags.centres_m.items():
            if not self.board.contains(x, y, half_tag):
                raise InvalidInput(f"board_tags.centres_m.{tag_id}: ({x}, {y}) is not on the board")
        for place, (x, y) in self.places_m.items():
            if not self.board.contains(x, y):
                raise InvalidInput(f"places_m.{place}: ({x}, {y}) is not on the board")
        for tag_id, entry in self.block_tags.ids.items():
            if entry.destination not in self.places_m:
                raise InvalidInput(
                    f"block_tags.ids.{tag_id}.destination: place {entry.destination} is not in places_m {sorted(self.places_m)}"
                )
        marker = self.gripper.marker
        if marker is not None and (marker.id in self.board_tags.centres_m or marker.id >= dictionary_size(self.board_tags.detector)):
            raise ValueError(f"gripper.marker.id: {marker.id} is a board tag or not in {self.board_tags.detector}")
        overlap = set(self.board_tags.centres_m) & set(self.block_tags.ids)
        if overlap and self.board_tags.detector == self.block_tags.dictionary:
            raise InvalidInput(f"block_tags.ids: {sorted(overlap)} are also board tags of the same dictionary")
        if not self.board.contains(*self.feeder.spot_m, 0.5 * self.blocks.edges_m["large"]):
            raise InvalidInput(f"feeder.spot_m: {list(self.feeder.spot_m)} is not on the board")
        corners = [(x, y) for x in self.bin.x_range_m for y in self.bin.y_range_m]
        if not all(self.board.contains(x, y) for x, y in corners):
            raise InvalidInput("bin: the rectangle reaches outside the board")
        return self

    # ------------------------------------------------------------------ lookups
    def block_edge_m(self, size: str) -> float:
        """Edge of a cube of `size` ("large" or "small"), metres."""
        try:
            return float(self.blocks.edges_m[size])
        except KeyError:
            raise InvalidInput(f"block size must be one of {list(BLOCK_SIZES)}, got {size!r}") from None

    def object_dimensions_m(self, obj_type: str, size: str | None) -> tuple[float, float, float]:
        """(extent_x, extent_y, height) of a block or distractor in its body frame; size None = large."""
        if obj_type == "block":
            edge = self.block_edge_m(size or "large")
            return (edge, edge, edge)
        shape = self.distractors.shapes.get(obj_type)
        if shape is None:
            raise InvalidInput(f"unknown object type {obj_type!r}; distractors: {list(DISTRACTOR_SHAPES)}")
        if size not in (None, *BLOCK_SIZES):
            raise InvalidInput(f"size must be one of {list(BLOCK_SIZES)} or None, got {size!r}")
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
            raise InvalidInput(f"no place {destination!r}; places: {sorted(self.places_m)}")
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
