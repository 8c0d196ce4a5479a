"""Manipulation skills: plan a pick or a place (checked before anything moves), then run its steps
through the gate (armlab.station), which refuses them once the job is cancelled or e-stopped."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from armlab.station.core import Station
from armlab.station.jobs import JobContext


def plan_pick_steps(station: Station, top_center_m, yaw_rad: float | None, q_start_rad=None) -> list:
    """armlab.motion's pick plan from the current joints (open, above, straight down, grasp, straight up).

    Unreachable / UnsafeTrajectory / ValueError before anything moves.
    """
    from armlab.motion import plan_pick

    q_start = station.joints_rad() if q_start_rad is None else np.asarray(q_start_rad, float)
    return plan_pick(station.model, q_start, np.asarray(top_center_m, float), 0.0 if yaw_rad is None else yaw_rad, station.motion_config)


def plan_place_steps(station: Station, surface_m, yaw_rad: float | None, held_height_m: float, q_start_rad=None) -> list:
    """armlab.motion's place plan: the held block's bottom centre onto surface_m, then release and retreat."""
    from armlab.motion import plan_place

    q_start = station.joints_rad() if q_start_rad is None else np.asarray(q_start_rad, float)
    yaw = 0.0 if yaw_rad is None else yaw_rad
    return plan_place(station.model, q_start, np.asarray(surface_m, float), yaw, station.motion_config, held_height_m)


def run_steps(station: Station, ctx: JobContext, steps: Sequence, replan: Callable[[], list] | None = None,
              progress: bool = True) -> None:
    """Execute motion steps (TrajectoryStep / GripperStep) through the gate, reporting progress.

    If the arm is no longer where the plan starts (it moved since planning), `replan()` plans again.
    """
    from armlab.motion import TrajectoryStep

    first = next((step for step in steps if isinstance(step, TrajectoryStep)), None)
    if replan is not None and first is not None and np.abs(first.trajectory.positions_rad[0] - station.joints_rad()).max() > 0.01:
        steps = replan()
    for index, step in enumerate(steps):
        if progress:
            ctx.progress(index / len(steps), step.name)
        if isinstance(step, TrajectoryStep):
            station.run_trajectory(ctx, step.trajectory)
        else:
            station.run_gripper(ctx, step.action)
    if progress:
        ctx.progress(1.0, "done")
