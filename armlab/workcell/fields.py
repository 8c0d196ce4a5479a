"""Field types shared by the workcell config's sections (lengths, points) and the check of a (lower, upper) range."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from armlab.errors import InvalidInput

Positive = Annotated[float, Field(gt=0.0)]
Length = Annotated[float, Field(gt=0.0, lt=1.0)]  # an object or tag dimension, metres
Point2 = tuple[float, float]


def ordered(name: str, bounds: tuple[float, float]) -> None:
    """InvalidInput unless bounds[0] < bounds[1]."""
    if not bounds[0] < bounds[1]:
        raise InvalidInput(f"{name}: lower bound {bounds[0]} must be below upper bound {bounds[1]}")
