"""`forwarded`: a Station attribute answered by one of the parts it owns, declared in one line so the part's own
method (and its docstring) is the one place the behaviour is written."""

from __future__ import annotations

from operator import attrgetter
from typing import Any


class forwarded:  # noqa: N801 - used like `property`
    """`run_trajectory = forwarded("gate")` in a class body: instance.run_trajectory reads instance.gate.run_trajectory
    (a method bound to the part, or a property's value); `forwarded("trust", "install")` names it differently.
    Not a data descriptor: a test may still set the attribute on one instance."""

    def __init__(self, part: str, name: str | None = None) -> None:
        self._part, self._name = part, name

    def __set_name__(self, owner: type, name: str) -> None:
        self._get = attrgetter(f"{self._part}.{self._name or name}")

    def __get__(self, instance: Any, owner: type | None = None) -> Any:
        return self if instance is None else self._get(instance)
