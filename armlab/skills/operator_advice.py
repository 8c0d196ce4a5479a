"""What the operator can do when a click-grab or click-drop cannot be done (issue 21): the planner's reason put in
the operator's terms (the clicked spot and what is wrong there) and the next step, instead of the planner's
figures alone ('gripper point at z = 3.0 mm ... below ... + clearance (3.0 mm)' for a far click)."""

from __future__ import annotations

import re

from armlab.errors import Unreachable
from armlab.motion.safety import UnsafeTrajectory

NEARER = "click a spot nearer the arm"
FARTHER = "click a spot farther from the arm's base"
ELSEWHERE = "click a spot within the arm's reach"
_SPAN = re.compile(r"wrist centre ([\d.]+) m from the shoulder; the arm spans [\d.]+\.\.([\d.]+) m")
_INTO_BOARD = re.compile(r"go ([\d.]+) mm into the board")


def _spot(point_m) -> str:
    return f"({point_m[0] * 1000:.0f}, {point_m[1] * 1000:.0f}) mm"


def advised(what: str, point_m, error: Exception, base_xy_m=None) -> Exception | None:
    """`error` (a plan's or a motion check's refusal of `what` at point_m) said with the operator's next step, as
    the same error type (the same HTTP answer); None when there is nothing better to say than the error."""
    text = str(error)
    where = f"{what} at {_spot(point_m)}"
    if isinstance(error, Unreachable):
        if error.reason == "out of reach":
            span = _SPAN.search(text)
            flat = " with the suction cup flat on top" if "suction cup seals only flat" in text else ""
            if span:  # the wrist's distance against the arm's span says which way to go
                wrist_mm, reach_mm = float(span[1]) * 1000, float(span[2]) * 1000
                figures = f" (its wrist would be {wrist_mm:.0f} mm from the shoulder; it reaches {reach_mm:.0f} mm)"
                return Unreachable(f"{where}: out of the arm's reach{flat}{figures}: {NEARER if wrist_mm > reach_mm else FARTHER}",
                                   error.reason)
            base = ""
            if base_xy_m is not None:
                base = f" ({((point_m[0] - base_xy_m[0]) ** 2 + (point_m[1] - base_xy_m[1]) ** 2) ** 0.5 * 1000:.0f} mm from its base)"
            return Unreachable(f"{where}: out of the arm's reach{flat}{base}: {ELSEWHERE}", error.reason)
        if error.reason == "below the table":
            return Unreachable(f"{where}: the gripper would have to go below the board there: {NEARER}", error.reason)
        return None
    if isinstance(error, UnsafeTrajectory):
        into = _INTO_BOARD.search(text)
        if into is not None or "below the board" in text:
            depth = f" ({into[1]} mm into it)" if into else ""
            return UnsafeTrajectory(f"{where}: the gripper cannot come straight down there; on its way down it would "
                                    f"touch the board{depth}: {NEARER}")
    return None
