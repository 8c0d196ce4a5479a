"""Input checks for station commands: pure functions raising ValueError with a sentence naming the field."""

from __future__ import annotations

import math

import numpy as np

from armlab.errors import InvalidInput, RefusedByCheck


class NotCalibrated(RefusedByCheck, RuntimeError):
    """The command needs a camera calibration: run calibrate first."""

    def __init__(self, what: str = "this command") -> None:
        super().__init__(f"{what} needs a camera calibration: calibrate first")


def checked_joints(model, q_rad) -> np.ndarray:
    """A finite (dof,) joint vector within `model`'s limits, else ValueError naming the joint."""
    q = np.asarray(q_rad, dtype=float)
    dof = int(model.dof)
    if q.shape != (dof,):
        raise InvalidInput(f"q_rad must have {dof} values ({', '.join(model.joint_names)}), got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise InvalidInput("q_rad must be finite numbers")
    lower, upper = np.asarray(model.lower_rad), np.asarray(model.upper_rad)
    for index, name in enumerate(model.joint_names):
        if not lower[index] - 1e-9 <= q[index] <= upper[index] + 1e-9:
            raise InvalidInput(
                f"joint '{name}' = {q[index]:.4f} rad is outside its limits [{lower[index]:.4f}, {upper[index]:.4f}] rad"
            )
    return q


def checked_moving_time(moving_time_s: float | None, max_moving_time_s: float) -> float | None:
    """None (as fast as the limits allow) or a finite duration in (0, max_moving_time_s]."""
    if moving_time_s is None:
        return None
    value = float(moving_time_s)
    if not math.isfinite(value) or not 0.0 < value <= max_moving_time_s:
        raise InvalidInput(f"moving_time_s must be in (0, {max_moving_time_s}] s, got {moving_time_s}")
    return value


def checked_position(position_m) -> np.ndarray:
    """Three finite coordinates in metres (x, y, z, world frame)."""
    position = np.asarray(position_m, dtype=float) if position_m is not None else None
    if position is None or position.shape != (3,) or not np.all(np.isfinite(position)):
        raise InvalidInput(f"position_m must be 3 finite numbers (x, y, z in metres), got {position_m!r}")
    return position
