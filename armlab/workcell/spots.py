"""Where the jobs and the scene generators put things: the to_the_sky feeder, the clear_table bin and the
generators' reach."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from armlab.config import StrictModel
from armlab.errors import InvalidInput
from armlab.workcell.fields import Length, Point2, ordered


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
        ordered("x_range_m", self.x_range_m)
        ordered("y_range_m", self.y_range_m)
        return self

    @property
    def centre_m(self) -> Point2:
        return (0.5 * sum(self.x_range_m), 0.5 * sum(self.y_range_m))

    def contains(self, x_m: float, y_m: float) -> bool:
        return self.x_range_m[0] <= x_m <= self.x_range_m[1] and self.y_range_m[0] <= y_m <= self.y_range_m[1]


DEFAULT_SCENE_REACH_M = (0.13, 0.36)  # the RX200's comfortable top-down reach (radius from the base axis)


class SceneSpec(StrictModel):
    """Where the scene generators (armlab.scene) put objects: reach_m = (min, max) radius from the arm's
    base axis within which a top-down pick reaches comfortably."""

    reach_m: tuple[float, float] = DEFAULT_SCENE_REACH_M

    @model_validator(mode="after")
    def _check(self) -> SceneSpec:
        if not 0.0 <= self.reach_m[0] < self.reach_m[1] <= 5.0:
            raise InvalidInput(f"reach_m: need 0 <= min < max <= 5 m, got {list(self.reach_m)}")
        return self
