"""Perception configuration: config/vision.yaml (colour classes, thresholds, calibration limits, depth
objects) filled with the workcell's facts (board and grid, tag dictionary and layout, block sizes,
block-top tag mapping) from config/workcells/<name>.yaml, which vision.yaml names and must not copy.
Validated at load time so a typo fails at start-up, not mid-job."""

from __future__ import annotations

import math
import re
from pathlib import Path

import cv2
import numpy as np
from pydantic import Field, field_validator, model_validator

from armlab.config import StrictModel, config_dir, read_config_file, validate_config
from armlab.errors import ConfigError
from armlab.workcell import DEFAULT_WORKCELL, Workcell, load_workcell
from armlab.workcell.objects import BlockTagEntry
from armlab.workcell.tag_families import is_apriltag_family, known_family

COLOR_NAME = re.compile(r"[a-z][a-z0-9_]{0,31}")

__all__ = ["BlockTagEntry", "PerceptionConfig", "TagDetectionConfig", "is_apriltag_family", "load_perception_config",
           "workcell_sections"]


class TagDetectionConfig(StrictModel):
    """Tag decoder thresholds (vision.yaml tag_detection). AprilTag library: detections with more
    corrected bits than max_hamming or a decision margin below min_decision_margin are dropped
    (max_hamming 2 is the library's own default); quad_decimate 1 keeps ~20 px tags readable.
    ArUco: aruco_error_correction_rate (OpenCV's)."""

    max_hamming: int = Field(2, ge=0, le=3)
    min_decision_margin: float = Field(25.0, ge=0.0)
    quad_decimate: float = Field(1.0, ge=1.0, le=4.0)
    quad_sigma: float = Field(0.0, ge=0.0, le=2.0)
    decode_sharpening: float = Field(0.25, ge=0.0, le=1.0)
    aruco_error_correction_rate: float = Field(0.6, ge=0.0, le=1.0)


class TagConfig(StrictModel):
    """Filled from the workcell: board tags (dictionary = what decodes them: an AprilTag family or an
    OpenCV DICT_ name; size, id -> centre) and block-top tags."""

    dictionary: str
    board_tag_size_m: float = Field(gt=0.0, lt=1.0)
    board_tags: dict[int, tuple[float, float]]
    block_tag_dictionary: str
    block_tags: dict[int, BlockTagEntry] = {}

    @field_validator("dictionary")
    @classmethod
    def _known_family(cls, name: str) -> str:
        return known_family(name)

    @field_validator("block_tag_dictionary")
    @classmethod
    def _known_dictionary(cls, name: str) -> str:
        if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
            raise ValueError(f"unknown OpenCV ArUco dictionary '{name}' (e.g. DICT_APRILTAG_36h11, DICT_4X4_50)")
        return name

    @model_validator(mode="after")
    def _enough_tags(self) -> TagConfig:
        if len(self.board_tags) < 3:
            raise ValueError("board_tags needs at least 3 tags for a calibration")
        overlap = set(self.board_tags) & set(self.block_tags)
        if overlap and self.dictionary == self.block_tag_dictionary:
            raise ValueError(f"ids {sorted(overlap)} are both board tags and block tags")
        return self


class CalibrationLimits(StrictModel):
    """Limits a new calibration must meet, and the camera-moved check of a calibration in use: every
    drift_check_period_s the board tags' image centres are compared with where the calibration puts
    them; a median drift above drift_threshold_px on drift_confirm_checks checks in a row warns."""

    max_reprojection_error_px: float = Field(3.0, gt=0.0)
    max_depth_check_error_m: float = Field(0.02, gt=0.0)
    drift_threshold_px: float = Field(2.0, gt=0.0)
    drift_check_period_s: float = Field(3.0, gt=0.0)
    drift_confirm_checks: int = Field(2, ge=1, le=10)


class BoardConfig(StrictModel):
    """Filled from the workcell's board and grid."""

    x_range_m: tuple[float, float]
    y_range_m: tuple[float, float]
    grid_x_m: tuple[float, float]
    grid_y_m: tuple[float, float]
    grid_step_m: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _ordered(self) -> BoardConfig:
        for name in ("x_range_m", "y_range_m", "grid_x_m", "grid_y_m"):
            low, high = getattr(self, name)
            if not low < high:
                raise ValueError(f"{name}: lower bound {low} must be below upper bound {high}")
        return self

    def grid_points_m(self) -> np.ndarray:
        """The board's grid points (N, 3) at z = 0, row by row."""
        xs = np.arange(self.grid_x_m[0], self.grid_x_m[1] + 1e-9, self.grid_step_m)
        ys = np.arange(self.grid_y_m[0], self.grid_y_m[1] + 1e-9, self.grid_step_m)
        gx, gy = np.meshgrid(xs, ys)
        return np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)


class BlockConfig(StrictModel):
    """Sizes filled from the workcell's block edges; the rest (colour classes, thresholds) is vision's."""

    large_size_m: float = Field(gt=0.0)
    small_size_m: float = Field(gt=0.0)
    min_height_m: float = Field(0.008, gt=0.0)
    max_height_m: float = Field(0.55, gt=0.0)
    top_face_tolerance_m: float = Field(0.006, gt=0.0)
    stack_height_tolerance_m: float = Field(0.008, gt=0.0)
    min_saturation: int = Field(70, ge=0, le=255)
    min_value: int = Field(40, ge=0, le=255)
    colors: dict[str, float]

    @model_validator(mode="after")
    def _sane(self) -> BlockConfig:
        if not self.small_size_m < self.large_size_m:
            raise ValueError("small_size_m must be below large_size_m")
        if not self.min_height_m < self.max_height_m:
            raise ValueError("min_height_m must be below max_height_m")
        if len(self.colors) < 1:
            raise ValueError("colors must name at least one colour")
        for name, hue in self.colors.items():
            if not 0.0 <= hue < 180.0:
                raise ValueError(f"colors.{name}: hue {hue} outside OpenCV's 0..180")
        return self


class ColorModelConfig(StrictModel):
    """Block colour classes in board-normalised CIELAB (armlab.vision.colors): references per class
    (measured on real frames and on the simulation's renders: bench/color_references.py), the
    distance beyond which a face is `unknown`, and the extra colour names an operator may teach the
    station (colour calibration) besides the classes."""

    board_reflectance: float = Field(0.5, gt=0.0, le=1.0)
    k_lightness: float = Field(2.0, gt=0.0)
    k_chroma: float = Field(2.0, gt=0.0)
    max_distance: float = Field(15.0, gt=0.0)
    min_chroma: float = Field(10.0, ge=0.0)
    references: dict[str, tuple[tuple[float, float, float], ...]]
    extra_names: tuple[str, ...] = ()

    @model_validator(mode="after")
    def _sane(self) -> ColorModelConfig:
        for name, refs in self.references.items():
            if not refs:
                raise ValueError(f"references.{name}: needs at least one reference colour [L, a, b]")
            for i, ref in enumerate(refs):
                if not all(math.isfinite(x) for x in ref) or not 0.0 <= ref[0] <= 200.0:
                    raise ValueError(f"references.{name}[{i}]: {list(ref)} is not a CIELAB colour (finite, L in 0..200)")
        for name in (*self.references, *self.extra_names):
            if not COLOR_NAME.fullmatch(name) or name == "unknown":
                raise ValueError(f"colour name '{name}': lower-case letters, digits and _ only, and not 'unknown'")
        clash = set(self.references) & set(self.extra_names)
        if clash:
            raise ValueError(f"extra_names: {sorted(clash)} are classes already")
        return self


class BoardPlaneConfig(StrictModel):
    """The board plane fitted in each depth image (armlab.vision.board_plane): board pixels whose height
    above the tags' plane is within window_m (the depth camera's offset; real L515s: 7-12 mm, measured on
    the ROB 550 frames), inliers within inlier_m (about 3x the depth noise on the board: 1.2-1.7 mm RMS
    on those frames). enabled: false measures heights from the tags' plane (the calibration's correction)."""

    enabled: bool = True
    window_m: float = Field(0.03, gt=0.0, lt=0.2)
    inlier_m: float = Field(0.004, gt=0.0, lt=0.05)
    min_inlier_fraction: float = Field(0.5, gt=0.0, le=1.0)


class ObjectConfig(StrictModel):
    min_height_m: float = Field(0.008, gt=0.0)
    ransac_iterations: int = Field(200, ge=10)
    ransac_threshold_m: float = Field(0.004, gt=0.0)
    cluster_distance_m: float = Field(0.01, gt=0.0)
    min_points: int = Field(30, ge=1)


class SelfFilterConfig(StrictModel):
    """The robot self-filter (armlab.vision.self_filter): the arm's volume, inflated, that perception
    ignores: the arm's body, its links' capsules grown by margin_m, the base's housings and the box around the
    gripper's parts by box_margin_m (blocks that are the scene stand close beside the base and under a hovering
    gripper); a held block a cube between the fingers, grown by held_block_margin_m."""

    enabled: bool = True
    margin_m: float = Field(0.022, ge=0.0, lt=0.2)  # the arm's links' capsules (armlab.devices.arm_body) grown this much
    box_margin_m: float = Field(0.007, ge=0.0, lt=0.2)  # the base's housings and the box around the gripper's parts
    held_block_edge_m: float = Field(0.038, ge=0.0, lt=0.5)
    held_block_margin_m: float = Field(0.01, ge=0.0, lt=0.1)
    pixel_step: int = Field(2, ge=1, le=8)


class PerceptionConfig(StrictModel):
    """Everything perception needs besides the camera intrinsics (workcell = the config it was filled from)."""

    workcell: str = DEFAULT_WORKCELL
    tags: TagConfig
    tag_detection: TagDetectionConfig = TagDetectionConfig()
    calibration: CalibrationLimits = CalibrationLimits()
    board: BoardConfig
    blocks: BlockConfig
    objects: ObjectConfig = ObjectConfig()
    color_model: ColorModelConfig
    board_plane: BoardPlaneConfig = BoardPlaneConfig()
    self_filter: SelfFilterConfig = SelfFilterConfig()

    @model_validator(mode="after")
    def _block_tag_colours_known(self) -> PerceptionConfig:
        for tag_id, entry in self.tags.block_tags.items():
            if entry.color not in self.blocks.colors:
                raise ValueError(f"tags.block_tags.{tag_id}: colour '{entry.color}' is not in blocks.colors")
        if set(self.color_model.references) != set(self.blocks.colors):
            raise ValueError(f"color_model.references: classes {sorted(self.color_model.references)} must be the "
                             f"block colours {sorted(self.blocks.colors)}")
        return self

    def board_tag_corners_m(self, tag_id: int) -> np.ndarray:
        """World corners (4, 3) of a board tag in OpenCV corner order (TL, TR, BR, BL seen from above, +y up)."""
        cx, cy = self.tags.board_tags[tag_id]
        h = self.tags.board_tag_size_m / 2.0
        return np.array([[cx - h, cy + h, 0.0], [cx + h, cy + h, 0.0], [cx + h, cy - h, 0.0], [cx - h, cy - h, 0.0]])


# vision.yaml fields that are workcell facts: filled from the workcell config, never written in vision.yaml.
WORKCELL_FIELDS = {
    "tags": ("dictionary", "board_tag_size_m", "board_tags", "block_tag_dictionary", "block_tags"),
    "board": ("x_range_m", "y_range_m", "grid_x_m", "grid_y_m", "grid_step_m"),
    "blocks": ("large_size_m", "small_size_m"),
}


def workcell_sections(workcell: Workcell) -> dict[str, dict]:
    """The PerceptionConfig fields a workcell fills (see WORKCELL_FIELDS), in vision's names."""
    board = workcell.board
    return {
        "tags": {
            "dictionary": workcell.board_tags.detector,
            "board_tag_size_m": workcell.board_tags.size_m,
            "board_tags": dict(workcell.board_tags.centres_m),
            "block_tag_dictionary": workcell.block_tags.dictionary,
            "block_tags": dict(workcell.block_tags.ids),
        },
        "board": {
            "x_range_m": board.x_range_m,
            "y_range_m": board.y_range_m,
            "grid_x_m": board.grid.x_m,
            "grid_y_m": board.grid.y_m,
            "grid_step_m": board.grid.step_m,
        },
        "blocks": {"large_size_m": workcell.block_edge_m("large"), "small_size_m": workcell.block_edge_m("small")},
    }


def load_perception_config(path: str | Path | None = None, workcell: str | Workcell | None = None) -> PerceptionConfig:
    """Load config/vision.yaml (or `path`) and fill it from the workcell it names (`workcell:`, default
    rx200_armlab; the argument overrides it). ConfigError naming the file and field when either is
    invalid, or when vision.yaml copies a workcell fact."""
    path = Path(path) if path is not None else config_dir() / "vision.yaml"
    data = read_config_file(path)
    name = data.get("workcell", DEFAULT_WORKCELL)
    if not isinstance(name, str):
        raise ConfigError(f"{path}: invalid config: workcell: expected the name of a config/workcells/ file, got {name!r}")
    for section, fields in WORKCELL_FIELDS.items():
        values = data.get(section)
        copied = [field for field in fields if isinstance(values, dict) and field in values]
        if copied:
            raise ConfigError(
                f"{path}: invalid config: {section}.{copied[0]}: is a workcell fact; set it in "
                f"config/workcells/{name}.yaml, not in vision.yaml (one fact, one place)"
            )
    cell = workcell if isinstance(workcell, Workcell) else load_workcell(workcell or name)
    merged = {**data, "workcell": cell.name}
    for section, values in workcell_sections(cell).items():
        own = data.get(section, {})
        merged[section] = {**own, **values} if isinstance(own, dict) else own
    return validate_config(merged, PerceptionConfig, str(path))
