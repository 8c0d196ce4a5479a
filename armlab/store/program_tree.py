"""A program's step tree (the tree a pendant shows) and its expansion into the flat waypoint sequence.

A program's steps are waypoints (as always), `wait` (seconds), `gripper` (open/close), `loop` (count
1..MAX_LOOP_COUNT, a body of steps) and `group` (a label, a body of steps), nested at most MAX_DEPTH deep.
Repeat plans the flat sequence expand() returns, exactly as it plans a taught list of waypoints, so the
motion checks and the speed override are unchanged:

- a waypoint is itself;
- a wait adds its seconds to the dwell of the waypoint before it (a wait before any waypoint is refused);
- a gripper step is a waypoint at the previous waypoint's joints with the gripper closed ('grasp') or
  opened ('release'): repeat stops there and runs the gripper (a gripper step before any waypoint is refused);
- a loop is its body expanded count times; a group is its body, once.

A program of waypoints only is a flat list, stored and exported exactly as before. Pure functions: no
station, no database. Every limit is InvalidInput naming the step by its path (e.g. steps[2].body[0]).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from armlab.errors import InvalidInput
from armlab.store.waypoint import MAX_DWELL_S, Waypoint

MAX_DEPTH = 4  # loops and groups inside one another: at most this many levels
MAX_LOOP_COUNT = 1000
MAX_EXPANDED_WAYPOINTS = 1000  # the flat sequence repeat plans (the same limit as a taught list)
MAX_LABEL_CHARS = 60
STEP_KINDS = ("waypoint", "wait", "gripper", "loop", "group")
GRIPPER_ACTIONS = {"close": "grasp", "open": "release"}


@dataclass(frozen=True)
class Wait:
    seconds: float


@dataclass(frozen=True)
class Gripper:
    action: str  # 'open' | 'close'


@dataclass(frozen=True)
class Loop:
    count: int
    body: tuple


@dataclass(frozen=True)
class Group:
    label: str
    body: tuple


Step = Waypoint | Wait | Gripper | Loop | Group


def is_flat(steps: Sequence[Step]) -> bool:
    """True when every step is a waypoint (a program as taught: stored and exported as before)."""
    return all(isinstance(step, Waypoint) for step in steps)


def depth(steps: Sequence[Step]) -> int:
    """How many levels of loops and groups (0: none)."""
    return max((1 + depth(step.body) for step in steps if isinstance(step, (Loop, Group))), default=0)


def steps_from_list(items, path: str = "steps", level: int = 0) -> tuple[Step, ...]:
    """Steps from their JSON form (to_list's; an item without 'kind' is a waypoint); InvalidInput naming the path."""
    if not isinstance(items, list) or not items:
        raise InvalidInput(f"{path}: must be a non-empty list of steps")
    if level >= MAX_DEPTH + 1:
        raise InvalidInput(f"{path}: loops and groups are nested more than {MAX_DEPTH} deep")
    steps = []
    for index, item in enumerate(items):
        where = f"{path}[{index}]"
        if not isinstance(item, dict):
            raise InvalidInput(f"{where}: a step must be an object")
        kind = item.get("kind", "waypoint")
        fields = set(item) - {"kind"}
        try:
            if kind == "waypoint":
                steps.append(Waypoint.from_dict(item))
            elif kind == "wait":
                _only(where, fields, {"seconds"})
                steps.append(Wait(_seconds(item.get("seconds"), where)))
            elif kind == "gripper":
                _only(where, fields, {"action"})
                if item.get("action") not in GRIPPER_ACTIONS:
                    raise InvalidInput(f"{where}.action: must be 'open' or 'close', not {item.get('action')!r}")
                steps.append(Gripper(item["action"]))
            elif kind == "loop":
                _only(where, fields, {"count", "body"})
                count = item.get("count")
                if not isinstance(count, int) or isinstance(count, bool) or not 1 <= count <= MAX_LOOP_COUNT:
                    raise InvalidInput(f"{where}.count: a loop runs 1 to {MAX_LOOP_COUNT} times, not {count!r}")
                steps.append(Loop(count, steps_from_list(item.get("body"), f"{where}.body", level + 1)))
            elif kind == "group":
                _only(where, fields, {"label", "body"})
                label = item.get("label")
                if not isinstance(label, str) or not label.strip() or len(label) > MAX_LABEL_CHARS:
                    raise InvalidInput(f"{where}.label: a group needs a label of 1 to {MAX_LABEL_CHARS} characters")
                steps.append(Group(label.strip(), steps_from_list(item.get("body"), f"{where}.body", level + 1)))
            else:
                raise InvalidInput(f"{where}.kind: must be one of {', '.join(STEP_KINDS)}, not {kind!r}")
        except (KeyError, TypeError, ValueError) as error:
            if isinstance(error, InvalidInput) and str(error).startswith(where):
                raise
            raise InvalidInput(f"{where}: {error}") from None
    return tuple(steps)


def to_list(steps: Sequence[Step]) -> list[dict]:
    """The JSON form (waypoints as Waypoint.to_dict(), without 'kind': a flat program is the list it always was)."""
    out = []
    for step in steps:
        if isinstance(step, Waypoint):
            out.append(step.to_dict())
        elif isinstance(step, Wait):
            out.append({"kind": "wait", "seconds": step.seconds})
        elif isinstance(step, Gripper):
            out.append({"kind": "gripper", "action": step.action})
        elif isinstance(step, Loop):
            out.append({"kind": "loop", "count": step.count, "body": to_list(step.body)})
        else:
            out.append({"kind": "group", "label": step.label, "body": to_list(step.body)})
    return out


def expand(steps: Sequence[Step], limit: int = MAX_EXPANDED_WAYPOINTS) -> tuple[Waypoint, ...]:
    """The flat waypoint sequence repeat plans (see the module's docstring); InvalidInput when a wait or gripper
    step has no waypoint before it, a dwell exceeds MAX_DWELL_S, or the sequence exceeds `limit` waypoints."""
    if depth(steps) > MAX_DEPTH:
        raise InvalidInput(f"steps: loops and groups are nested {depth(steps)} deep; at most {MAX_DEPTH}")
    out: list[Waypoint] = []
    _expand_into(out, steps, "steps", limit)
    if not out:
        raise InvalidInput("steps: the program has no waypoint")
    return tuple(out)


def _expand_into(out: list[Waypoint], steps: Sequence[Step], path: str, limit: int) -> None:
    for index, step in enumerate(steps):
        where = f"{path}[{index}]"
        if isinstance(step, Waypoint):
            out.append(step)
        elif isinstance(step, (Wait, Gripper)):
            if not out:
                raise InvalidInput(f"{where}: a {'wait' if isinstance(step, Wait) else 'gripper step'} needs a waypoint before it")
            last = out[-1]
            if isinstance(step, Wait):
                dwell = last.dwell_s + step.seconds
                if dwell > MAX_DWELL_S:
                    raise InvalidInput(f"{where}: the waits at one waypoint add up to {dwell:g} s; at most {MAX_DWELL_S:g}")
                out[-1] = Waypoint(last.joints_rad, last.gripper, dwell, last.moving_time_s)
            else:
                out.append(Waypoint(last.joints_rad, GRIPPER_ACTIONS[step.action]))
        elif isinstance(step, Loop):
            for _ in range(step.count):
                _expand_into(out, step.body, f"{where}.body", limit)
        else:
            _expand_into(out, step.body, f"{where}.body", limit)
        if len(out) > limit:
            raise InvalidInput(f"{where}: the program expands to more than {limit} waypoints (loops multiply their bodies)")


def _seconds(value, where: str) -> float:
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(float(value)) or not 0 < value <= MAX_DWELL_S:
        raise InvalidInput(f"{where}.seconds: a wait is above 0 and at most {MAX_DWELL_S:g} s, not {value!r}")
    return float(value)


def _only(where: str, fields: set, allowed: set) -> None:
    unknown = fields - allowed
    if unknown:
        raise InvalidInput(f"{where}: unknown field(s) {', '.join(sorted(unknown))}")
