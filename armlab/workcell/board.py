"""The board section of a workcell: its rectangle and grid, and the calibration tags printed on it (inline or
a config/boards/<name>.yaml file)."""

from __future__ import annotations

import numpy as np
from pydantic import field_validator, model_validator

from armlab.config import StrictModel, read_config_file, resolve_config_path
from armlab.errors import InvalidInput
from armlab.workcell.fields import Length, Point2, ordered
from armlab.workcell.tag_families import dictionary_size, known_dictionary, known_family


class GridSpec(StrictModel):
    x_m: Point2
    y_m: Point2
    step_m: Length

    @model_validator(mode="after")
    def _check(self) -> GridSpec:
        ordered("x_m", self.x_m)
        ordered("y_m", self.y_m)
        return self


class BoardSpec(StrictModel):
    """The board rectangle (world x/y ranges, its surface at z = 0) and its grid points."""

    x_range_m: Point2
    y_range_m: Point2
    grid: GridSpec

    @model_validator(mode="after")
    def _check(self) -> BoardSpec:
        ordered("x_range_m", self.x_range_m)
        ordered("y_range_m", self.y_range_m)
        if not (self.x_range_m[1] - self.x_range_m[0] <= 4.0 and self.y_range_m[1] - self.y_range_m[0] <= 4.0):
            raise InvalidInput("board larger than 4 m: are the ranges in metres?")
        for axis, grid, board in (("x", self.grid.x_m, self.x_range_m), ("y", self.grid.y_m, self.y_range_m)):
            if grid[0] < board[0] - 1e-9 or grid[1] > board[1] + 1e-9:
                raise InvalidInput(f"grid.{axis}_m {list(grid)} reaches outside the board {list(board)}")
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
        return None if name is None else known_dictionary(name)

    @property
    def detector(self) -> str:
        """What decodes the tags: the OpenCV dictionary when one is set, else the family."""
        return self.dictionary or self.family

    @model_validator(mode="after")
    def _check(self) -> BoardTagsSpec:
        if len(self.centres_m) < 3:
            raise InvalidInput("centres_m needs at least 3 tags for a calibration")
        size = dictionary_size(self.detector)
        bad = [tag_id for tag_id in self.centres_m if not 0 <= tag_id < size]
        if bad:
            raise InvalidInput(f"centres_m: ids {bad} are not in {self.detector} (0..{size - 1})")
        return self


def board_file(name: str) -> dict:
    """The board_tags mapping of config/boards/<name>.yaml (ConfigError listing the boards if absent)."""
    data = read_config_file(resolve_config_path(name, "boards"))
    if not isinstance(data.get("board_tags"), dict):
        raise InvalidInput(f"config/boards/{name}.yaml has no board_tags mapping")
    return data["board_tags"]
