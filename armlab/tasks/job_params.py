"""Each autonomous job's parameters as a pydantic model: what a request may give, checked in one place (types,
ranges, names), and the list GET /api/auto/jobs shows. A job without parameters has NoParams (anything given is
refused with the field's name)."""

from __future__ import annotations

import typing
from typing import Literal

from pydantic import ConfigDict, Field, ValidationError

from armlab.config import StrictModel
from armlab.errors import InvalidInput
from armlab.scene import COLORS
from armlab.scene.model import SIZES

Position_m = Field(None, ge=-1.0, le=1.0, description="a board position (m), within 1 m of the origin")


class JobParams(StrictModel):
    """Base of the jobs' parameter models: unknown names refused, numbers finite, no string for a number."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True, strict=True)


class NoParams(JobParams):
    """A job without parameters."""


class StackHereParams(JobParams):
    """stack_here: where to stack (x_m, y_m; default the job's own spot) and which blocks (a colour, a size; default all)."""

    # Left out = the default; an explicit null is refused like any other wrong type (defaults are not validated).
    x_m: float = Position_m
    y_m: float = Position_m
    color: Literal[tuple(COLORS)] = None  # type: ignore[valid-type, assignment]
    size: Literal[tuple(SIZES)] = None  # type: ignore[valid-type, assignment]


def validated_params(job: str, model: type[JobParams], params) -> dict:
    """The parameters given (only those), validated by the job's model; InvalidInput naming the parameter and
    what is wrong (an unknown name lists the job's parameters)."""
    if params is None:
        return {}
    if not isinstance(params, dict):
        raise InvalidInput("params must be an object")
    try:
        return model.model_validate(params).model_dump(exclude_unset=True)
    except ValidationError as error:
        problem = error.errors()[0]
        name = ".".join(str(part) for part in problem["loc"]) or "params"
        if problem["type"] == "extra_forbidden":
            known = ", ".join(model.model_fields)
            raise InvalidInput(f"job '{job}' has no parameter {name!r}" + (f"; parameters: {known}" if known else "")) from None
        given = repr(problem.get("input"))
        given = given if len(given) <= 60 else given[:57] + "..."
        wanted = dict(param_types(model)).get(str(problem["loc"][0]) if problem["loc"] else "", "")
        raise InvalidInput(f"parameter {name!r} of job '{job}' must be a {wanted}: {problem['msg']}, got {given}") from None


def param_types(model: type[JobParams]) -> list[tuple[str, str]]:
    """(name, type name) of each parameter, as GET /api/auto/jobs lists them: the type a value must have (a
    choice of words is a str)."""
    result = []
    for name, field in model.model_fields.items():
        kind = field.annotation
        if typing.get_origin(kind) is typing.Union:  # X | None: X
            kind = next(arg for arg in typing.get_args(kind) if arg is not type(None))
        result.append((name, "str" if typing.get_origin(kind) is Literal else kind.__name__))
    return result


__all__ = ["JobParams", "NoParams", "StackHereParams", "param_types", "validated_params"]
