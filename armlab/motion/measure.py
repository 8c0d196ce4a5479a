"""Figures of a joint motion recorded at every control tick on the simulated clock (SimWorkcell's joint
recording): how hard the command and the measured joints accelerate, and whether the command jumps.

Accelerations are taken over a window (20 ms by default, two trajectory samples at 100 Hz): the arm
interpolates its 100 Hz samples linearly, so over a single 4 ms tick a legal plan shows 2.5x its true
acceleration at every sample corner. Pure: arrays in, numbers out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_WINDOW_S = 0.02


@dataclass(frozen=True)
class MotionFigures:
    """Per-joint peaks (shape (dof,)): command_accel_rad_s2 (second difference of the servo references over
    the window), measured_accel_rad_s2 (difference of the measured velocities over the window); step_rad:
    the largest change of one tick's commanded motion from the tick before (a jump of the command shows up
    here; smooth motion gives ~ accel * tick^2)."""

    command_accel_rad_s2: np.ndarray
    measured_accel_rad_s2: np.ndarray
    step_rad: np.ndarray

    def ratio(self, accel_limit_rad_s2) -> tuple[float, float]:
        """(command, measured) peak acceleration as a multiple of the limit, over all joints."""
        limit = np.asarray(accel_limit_rad_s2, dtype=float)
        return float(np.max(self.command_accel_rad_s2 / limit)), float(np.max(self.measured_accel_rad_s2 / limit))


def motion_figures(trace: dict, window_s: float = DEFAULT_WINDOW_S) -> MotionFigures:
    """MotionFigures of a joint recording ({"time_s", "reference_rad", "velocity_rad_s"}, one row per tick)."""
    times = np.asarray(trace["time_s"], dtype=float)
    reference = np.asarray(trace["reference_rad"], dtype=float)
    velocity = np.asarray(trace["velocity_rad_s"], dtype=float)
    dof = reference.shape[1] if reference.ndim == 2 else 0
    if len(times) < 3:
        zeros = np.zeros(dof)
        return MotionFigures(zeros, zeros, zeros)
    tick = float(np.median(np.diff(times)))
    w = max(1, int(round(window_s / tick)))
    if len(times) > 2 * w:
        span = (times[2 * w :] - times[: -2 * w])[:, None] / 2.0
        command = np.abs(reference[2 * w :] - 2.0 * reference[w:-w] + reference[: -2 * w]) / span**2
        measured = np.abs(velocity[w:] - velocity[:-w]) / (times[w:] - times[:-w])[:, None]
        command_peak, measured_peak = command.max(axis=0), measured.max(axis=0)
    else:
        command_peak = measured_peak = np.zeros(dof)
    steps = np.abs(np.diff(reference, n=2, axis=0)).max(axis=0)
    return MotionFigures(command_peak, measured_peak, steps)
