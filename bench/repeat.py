"""Repeat a 6-waypoint program for 100 cycles in the fast simulation and print its figures (issue 9).

    .venv/bin/python bench/repeat.py [--cycles 100] [--speed 100]

Figures: the cycle time and its drift (last − first cycle, target ≤ 1 ms; cycle starts are read on the
simulated clock, so wall-clock load does not enter), the peak joint velocity and acceleration of the
commanded motion against the limits (finite differences of the 100 Hz samples), the largest tracking
error (commanded − measured, from the job's trace), and the cycle time against the same program moved
with the stop-at-every-waypoint trapezoids (plan_joint_move, rest to rest) that repeat used before.
The station runs synchronously (armlab/tasks/episode.py's way): physics advances only while the job waits.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

# Six waypoints around the board (rad, rx200 joint order), none a stop: the gain of blending shows.
WAYPOINTS_RAD = [
    (0.0, -0.30, 0.30, 0.90, 0.0),
    (0.45, 0.05, 0.35, 1.00, 0.0),
    (0.90, 0.20, 0.10, 1.10, 0.3),
    (0.50, -0.20, -0.10, 1.20, 0.3),
    (-0.20, -0.40, 0.20, 0.90, 0.0),
    (-0.70, 0.00, 0.40, 0.80, -0.3),
]


def main(argv: list[str] | None = None) -> int:
    from armlab import skills
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.motion import plan_joint_move
    from armlab.motion.safety import finite_difference_rates
    from armlab.skills.repeat_plan import plan_cycle
    from armlab.station.config import StationConfig
    from armlab.station.core import Station
    from armlab.store import Store, Waypoint

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=100)
    parser.add_argument("--speed", type=float, default=100.0, help="speed override, percent")
    args = parser.parse_args(argv)

    config = StationConfig()
    model = load_arm(config.arm)
    waypoints = [Waypoint(q, "release") for q in WAYPOINTS_RAD]
    with tempfile.TemporaryDirectory(prefix="armlab-bench-") as tmp, SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=model, config=config, store=Store(Path(tmp) / "bench.sqlite3"),
                          sim=cell, backend="sim", synchronous=True)
        station.start()
        try:
            program = station.store.save_program("bench six", waypoints)
            plan = plan_cycle(station, program, args.speed)
            wall0, sim0 = time.monotonic(), cell.sim_time_s
            job = skills.repeat(station, program.id, cycles=args.cycles, speed_percent=args.speed)
            job.wait(3600)
            wall_s, sim_s = time.monotonic() - wall0, cell.sim_time_s - sim0
            if job.state != "succeeded":
                print(f"repeat {job.state}: {job.message}")
                return 1
            trace = job.control.trace.snapshot()
        finally:
            station.close()

    starts = np.asarray(job.result["cycle_starts_s"])
    cycle_times = np.diff(starts)
    dof = model.dof
    velocity_limit, accel_limit = np.asarray(model.velocity_limit_rad_s), np.asarray(model.accel_limit_rad_s2)
    peak_v, peak_a = np.zeros(dof), np.zeros(dof)
    for step in plan.steps:
        if step.kind == "move":
            velocity, accel = finite_difference_rates(step.run.trajectory)
            peak_v = np.maximum(peak_v, np.abs(velocity).max(axis=0))
            if len(accel):
                peak_a = np.maximum(peak_a, np.abs(accel).max(axis=0))
    samples = np.asarray(trace["samples"])
    tracking = np.abs(samples[:, 1 : 1 + dof] - samples[:, 1 + dof :]).max(axis=0) if len(samples) else np.zeros(dof)
    points = [np.asarray(q) for q in WAYPOINTS_RAD] + [np.asarray(WAYPOINTS_RAD[0])]
    trapezoid_s = sum(plan_joint_move(a, b, model).duration_s for a, b in zip(points, points[1:]))
    from armlab.motion.blend import arm_limits, plan_run

    limits = arm_limits(model, jerk_factor_per_s=30.0).scaled(args.speed / 100.0)
    stop_every_s = plan_run(np.array(points), limits, stop_everywhere=True, tick_s=cell.control_period_s).duration_s

    print(f"repeat bench: {len(waypoints)} waypoints, {args.cycles} cycles at {args.speed:g} % "
          f"({plan.blended_runs} of {plan.runs} runs blended), fast simulation")
    print(f"  simulated {sim_s:.1f} s in {wall_s:.1f} s wall ({sim_s / wall_s:.0f}x real time)")
    print(f"  cycle time: planned {plan.cycle_s:.4f} s; measured first {cycle_times[0]:.4f} s, last {cycle_times[-1]:.4f} s, "
          f"min {cycle_times.min():.4f}, max {cycle_times.max():.4f} s")
    print(f"  drift (last - first cycle): {1000 * (cycle_times[-1] - cycle_times[0]):+.3f} ms (target <= 1 ms); "
          f"{len(starts)} cycles took {starts[-1] - starts[0] + cycle_times[-1]:.3f} s = {len(starts)} x {plan.cycle_s:.4f} s "
          f"{'+' if starts[-1] - starts[0] + cycle_times[-1] - len(starts) * plan.cycle_s >= 0 else '-'}"
          f" {1000 * abs(starts[-1] - starts[0] + cycle_times[-1] - len(starts) * plan.cycle_s):.3f} ms")
    print("  peak commanded joint velocity / limit (rad/s):  "
          + ", ".join(f"{n} {v:.2f}/{lim:.2f}" for n, v, lim in zip(model.joint_names, peak_v, velocity_limit)))
    print("  peak commanded joint acceleration / limit (rad/s²): "
          + ", ".join(f"{n} {a:.2f}/{lim:.2f}" for n, a, lim in zip(model.joint_names, peak_a, accel_limit)))
    print(f"  largest velocity ratio {np.max(peak_v / velocity_limit):.3f}, acceleration ratio {np.max(peak_a / accel_limit):.3f} (<= 1)")
    print("  tracking error over the last cycle, max |commanded - measured| (mrad): "
          + ", ".join(f"{n} {1000 * e:.1f}" for n, e in zip(model.joint_names, tracking)))
    print(f"  cycle time vs stop-at-every-waypoint trapezoids: {plan.cycle_s:.3f} s vs {trapezoid_s:.3f} s "
          f"({100 * (1 - plan.cycle_s / trapezoid_s):.1f} % shorter); vs jerk-limited stops at every waypoint {stop_every_s:.3f} s "
          f"({100 * (1 - plan.cycle_s / stop_every_s):.1f} % shorter)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
