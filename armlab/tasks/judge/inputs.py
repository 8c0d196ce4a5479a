"""The judge's inputs checked: event and level (with each event's time limit), the truth, the simulated
time, the gripper path and the tag centres; InvalidInput naming what is wrong."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene import Scene, SceneObject
from armlab.scene.events import EVENTS
from armlab.tasks.judge.geometry import within_bound

# Simulated seconds allowed per event (DESIGN §7).
EVENT_LIMITS_S: dict[str, float] = {
    "pick_sort": 180.0,
    "pick_stack": 120.0,
    "line_up": 600.0,
    "stack_high": 600.0,
    "to_the_sky": 600.0,
    "sort_stack": 180.0,
}
_SORT_STACK_LEVELS = (1, 2, 3)  # judged even before armlab.scene.EVENTS lists sort_stack


def check_event_level(event: str, level: int) -> float:
    if event not in EVENT_LIMITS_S:
        raise InvalidInput(f"judge: unknown event {event!r}; events: {', '.join(EVENT_LIMITS_S)}")
    levels = EVENTS.get(event, _SORT_STACK_LEVELS if event == "sort_stack" else ())
    if isinstance(level, bool) or not isinstance(level, (int, np.integer)) or level not in levels:
        raise InvalidInput(f"judge: event {event!r} has levels {tuple(levels)}, not {level!r}")
    return EVENT_LIMITS_S[event]


def check_truth(truth, workcell: str | None = None) -> tuple[SceneObject, ...]:
    if not isinstance(truth, Mapping) or not isinstance(truth.get("objects"), list):
        raise InvalidInput("judge: truth must be a mapping with an 'objects' list (the SimWorkcell.truth() format)")
    try:
        return Scene.from_dict({"objects": [within_bound(obj) for obj in truth["objects"]]}, workcell=workcell).objects
    except (ValueError, TypeError) as error:
        raise InvalidInput(f"judge: malformed truth object: {error}") from error


def check_time(sim_time_s) -> float:
    try:
        value = float(sim_time_s)
    except (TypeError, ValueError):
        raise InvalidInput(f"judge: sim_time_s must be a number of seconds, got {sim_time_s!r}") from None
    if not math.isfinite(value) or value < 0.0:
        raise InvalidInput(f"judge: sim_time_s must be finite and >= 0, got {sim_time_s!r}")
    return value


def check_path(gripper_path_m) -> np.ndarray | None:
    if gripper_path_m is None:
        return None
    try:
        path = np.asarray(gripper_path_m, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput("judge: gripper_path_m must be an (N, 3) sequence of positions in metres") from None
    if path.size == 0:
        return np.zeros((0, 3))
    if path.ndim != 2 or path.shape[1] != 3 or not np.all(np.isfinite(path)):
        raise InvalidInput(f"judge: gripper_path_m must be (N, 3) finite positions in metres, got shape {path.shape}")
    return path


def check_tag_centres(tag_centres_m) -> np.ndarray:
    values = tag_centres_m.values() if isinstance(tag_centres_m, Mapping) else tag_centres_m
    try:
        centres = np.asarray(list(values), dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput("judge: tag_centres_m must be (x, y) pairs in metres") from None
    if centres.ndim != 2 or centres.shape[0] < 1 or centres.shape[1] != 2 or not np.all(np.isfinite(centres)):
        raise InvalidInput(f"judge: tag_centres_m must be one or more finite (x, y) pairs, got shape {centres.shape}")
    return centres
