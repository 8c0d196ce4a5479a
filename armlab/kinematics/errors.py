"""The kinematics error type: a target the arm cannot reach (defined with the rest of the hierarchy in armlab.errors)."""

from __future__ import annotations

from armlab.errors import Unreachable

__all__ = ["Unreachable"]
