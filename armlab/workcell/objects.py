"""The objects section of a workcell: block edges, distractor shapes and the ArUco ids on block tops."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, field_validator, model_validator

from armlab.config import StrictModel
from armlab.errors import InvalidInput
from armlab.workcell.fields import Length
from armlab.workcell.tag_families import dictionary_size, known_dictionary

DISTRACTOR_SHAPES = ("semicircle", "arch", "triangle", "cylinder")
BLOCK_SIZES = ("large", "small")


class BlockSpec(StrictModel):
    edges_m: dict[str, Length]

    @model_validator(mode="after")
    def _check(self) -> BlockSpec:
        if set(self.edges_m) != set(BLOCK_SIZES):
            raise InvalidInput(f"edges_m must give exactly {list(BLOCK_SIZES)}, got {sorted(self.edges_m)}")
        if not self.edges_m["small"] < self.edges_m["large"]:
            raise InvalidInput("edges_m: small must be below large")
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
            raise InvalidInput(f"shapes must describe exactly {list(DISTRACTOR_SHAPES)}, got {sorted(self.shapes)}")
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
        return known_dictionary(name)

    @model_validator(mode="after")
    def _check(self) -> BlockTagsSpec:
        size = dictionary_size(self.dictionary)
        bad = [tag_id for tag_id in self.ids if not 0 <= tag_id < size]
        if bad:
            raise InvalidInput(f"ids {bad} are not in {self.dictionary} (0..{size - 1})")
        return self
