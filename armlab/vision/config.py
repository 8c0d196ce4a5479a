"""Perception configuration (config/vision.yaml): tag dictionary and board layout, block colours and
sizes, tag-topped block mapping. Validated at load time so a typo fails at start-up, not mid-job."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from pydantic import Field, field_validator, model_validator

from armlab.config import StrictModel, config_dir, load_config


class BlockTagEntry(StrictModel):
    """What an ArUco id on a block's top face means."""

    color: str
    destination: int


class TagConfig(StrictModel):
    dictionary: str = "DICT_APRILTAG_36h11"
    board_tag_size_m: float = Field(0.025, gt=0.0, lt=1.0)
    board_tags: dict[int, tuple[float, float]]
    block_tag_dictionary: str = "DICT_4X4_250"
    block_tags: dict[int, BlockTagEntry] = {}

    @field_validator("dictionary", "block_tag_dictionary")
    @classmethod
    def _known_dictionary(cls, name: str) -> str:
        if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
            raise ValueError(f"unknown OpenCV ArUco dictionary '{name}' (e.g. DICT_APRILTAG_36h11, DICT_4X4_50)")
        return name

    @model_validator(mode="after")
    def _enough_tags(self) -> "TagConfig":
        if len(self.board_tags) < 3:
            raise ValueError("board_tags needs at least 3 tags for a calibration")
        overlap = set(self.board_tags) & set(self.block_tags)
        if overlap and self.dictionary == self.block_tag_dictionary:
            raise ValueError(f"ids {sorted(overlap)} are both board tags and block tags")
        return self


class CalibrationLimits(StrictModel):
    max_reprojection_error_px: float = Field(3.0, gt=0.0)
    max_depth_check_error_m: float = Field(0.02, gt=0.0)


class BoardConfig(StrictModel):
    x_range_m: tuple[float, float]
    y_range_m: tuple[float, float]
    grid_x_m: tuple[float, float]
    grid_y_m: tuple[float, float]
    grid_step_m: float = Field(gt=0.0)

    @model_validator(mode="after")
    def _ordered(self) -> "BoardConfig":
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
    large_size_m: float = Field(0.038, gt=0.0)
    small_size_m: float = Field(0.025, gt=0.0)
    min_height_m: float = Field(0.008, gt=0.0)
    max_height_m: float = Field(0.4, gt=0.0)
    top_face_tolerance_m: float = Field(0.006, gt=0.0)
    min_saturation: int = Field(70, ge=0, le=255)
    min_value: int = Field(40, ge=0, le=255)
    colors: dict[str, float]

    @model_validator(mode="after")
    def _sane(self) -> "BlockConfig":
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


class ObjectConfig(StrictModel):
    min_height_m: float = Field(0.008, gt=0.0)
    ransac_iterations: int = Field(200, ge=10)
    ransac_threshold_m: float = Field(0.004, gt=0.0)
    cluster_distance_m: float = Field(0.01, gt=0.0)
    min_points: int = Field(30, ge=1)


class PerceptionConfig(StrictModel):
    """Everything perception needs besides the camera intrinsics."""

    tags: TagConfig
    calibration: CalibrationLimits = CalibrationLimits()
    board: BoardConfig
    blocks: BlockConfig
    objects: ObjectConfig = ObjectConfig()

    @model_validator(mode="after")
    def _block_tag_colours_known(self) -> "PerceptionConfig":
        for tag_id, entry in self.tags.block_tags.items():
            if entry.color not in self.blocks.colors:
                raise ValueError(f"tags.block_tags.{tag_id}: colour '{entry.color}' is not in blocks.colors")
        return self

    def board_tag_corners_m(self, tag_id: int) -> np.ndarray:
        """World corners (4, 3) of a board tag in OpenCV corner order (TL, TR, BR, BL seen from above, +y up)."""
        cx, cy = self.tags.board_tags[tag_id]
        h = self.tags.board_tag_size_m / 2.0
        return np.array([[cx - h, cy + h, 0.0], [cx + h, cy + h, 0.0], [cx + h, cy - h, 0.0], [cx - h, cy - h, 0.0]])


def load_perception_config(path: str | Path | None = None) -> PerceptionConfig:
    """Load config/vision.yaml (or `path`); ConfigError naming the file and field when invalid."""
    return load_config(Path(path) if path is not None else config_dir() / "vision.yaml", PerceptionConfig)
