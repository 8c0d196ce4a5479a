"""The kinematics error type: a target the arm cannot reach, with the reason in words."""

from __future__ import annotations


class Unreachable(ValueError):
    """No joint vector reaches the target within the limits.

    The message says why: "out of reach", "joint limit (<joint name>)" or "below the table", with the
    numbers. `reason` holds that short phrase alone, for callers that branch on it.
    """

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason
