"""The judge's verdict and its lines (Rule, Score), and the rule texts several events share: a tipped block,
the level bonus, millimetres."""

from __future__ import annotations

import math
from dataclasses import dataclass

from armlab.scene import SceneObject
from armlab.tasks.judge.geometry import tilt_rad


@dataclass(frozen=True)
class Rule:
    """One line of the breakdown: which rule gave how many points for which objects, and why."""

    rule: str
    points: int
    detail: str
    object_ids: tuple[str, ...] = ()

    def to_dict(self) -> dict:
        return {"rule": self.rule, "points": self.points, "detail": self.detail, "object_ids": list(self.object_ids)}


@dataclass(frozen=True)
class Score:
    """The judge's verdict; `full` = every point earned within the time limit."""

    points: int
    max_points: int
    within_limit: bool
    full: bool
    breakdown: tuple[Rule, ...]
    time_limit_s: float

    def to_dict(self) -> dict:
        return {
            "points": self.points,
            "max_points": self.max_points,
            "within_limit": self.within_limit,
            "full": self.full,
            "time_limit_s": self.time_limit_s,
            "breakdown": [rule.to_dict() for rule in self.breakdown],
        }


def mm(value_m: float) -> str:
    return f"{1000.0 * value_m:.0f} mm"


def tipped(block: SceneObject, rule: str) -> Rule:
    return Rule(rule, 0, f"tipped {math.degrees(tilt_rad(block)):.0f}° from vertical", (block.id,))


def bonus_rule(points: int, within_limit: bool, limit_s: float, block_rules: list[Rule], *reasons: str) -> Rule:
    """The level bonus: needs the end within the limit, every block scoring, and no other reason against it."""
    missing = [rule.object_ids[0] for rule in block_rules if rule.points == 0]
    why = [reason for reason in reasons if reason]
    if not within_limit:
        why.append(f"over the {limit_s:.0f} s limit")
    if missing:
        why.append(f"{len(missing)} of {len(block_rules)} blocks not scoring")
    if why:
        return Rule("bonus", 0, "level bonus lost: " + "; ".join(why), tuple(missing))
    return Rule("bonus", points, "level bonus: every block scored within the time limit")
