"""Motion-planning benchmark: planning time and limit compliance over seeded random moves and picks.

Prints figures (never asserts on wall time). Targets: a joint move plans in < 2 ms, a full pick
plan (IK chain + two vertical segments + safety checks) in < 100 ms, every plan within the joint
limits, and picks within reach planned top-down whenever that is reachable.

Run: .venv/bin/python bench/bench_motion.py [--moves 500] [--picks 60] [--seed 0]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from armlab.kinematics import Unreachable, load_arm
from armlab.motion import (
    GripperStep,
    check_trajectory,
    load_motion_config,
    plan_joint_move_timed,
    plan_pick,
)
from armlab.motion.cartesian import gripper_pitch_rad
from armlab.motion.safety import finite_difference_rates


def _worst_ratio(arm, trajectory) -> float:
    velocity, accel = finite_difference_rates(trajectory)
    ratios = [np.max(np.abs(velocity) / arm.velocity_limit_rad_s)]
    if accel.size:
        ratios.append(np.max(np.abs(accel) / arm.accel_limit_rad_s2))
    return float(max(ratios))


def bench_moves(arm, rng, count: int) -> None:
    times_ms, worst, clamped = [], 0.0, 0
    for _ in range(count):
        q_start = rng.uniform(arm.lower_rad, arm.upper_rad)
        q_goal = rng.uniform(arm.lower_rad, arm.upper_rad)
        moving_time = None if rng.random() < 0.5 else float(rng.uniform(0.2, 4.0))
        started = time.perf_counter()
        trajectory, timing = plan_joint_move_timed(q_start, q_goal, arm, moving_time_s=moving_time)
        times_ms.append((time.perf_counter() - started) * 1000)
        worst = max(worst, _worst_ratio(arm, trajectory))
        clamped += bool(timing.clamped)
    print(f"joint moves: {count} random start/goal pairs")
    print(f"  plan time: median {np.median(times_ms):.3f} ms, p95 {np.percentile(times_ms, 95):.3f} ms (target < 2 ms)")
    print(f"  worst finite-difference velocity/acceleration over limit: {worst:.6f} (must be ≤ 1)")
    print(f"  requests stretched to respect the limits: {clamped}")


def bench_picks(arm, rng, count: int) -> None:
    config = load_motion_config()
    times_ms, top_down, shallow, unreachable, worst = [], 0, 0, 0, 0.0
    durations = []
    for _ in range(count):
        radius = rng.uniform(0.12, 0.42)
        angle = rng.uniform(-math.pi / 2, math.pi / 2)
        top = np.array([radius * math.sin(angle), radius * math.cos(angle), rng.choice([0.025, 0.038])])
        yaw = float(rng.uniform(-math.pi / 4, math.pi / 4))
        started = time.perf_counter()
        try:
            steps = plan_pick(arm, arm.home_rad, top, yaw, config)
        except Unreachable:
            unreachable += 1
            continue
        times_ms.append((time.perf_counter() - started) * 1000)
        trajectories = [step.trajectory for step in steps if not isinstance(step, GripperStep)]
        for trajectory in trajectories:
            check_trajectory(arm, trajectory, clearance_m=config.board_clearance_m)
            worst = max(worst, _worst_ratio(arm, trajectory))
        durations.append(sum(t.duration_s for t in trajectories))
        pitch = gripper_pitch_rad(arm, trajectories[1].positions_rad[-1])
        if abs(pitch - math.pi / 2) < 1e-3:
            top_down += 1
        else:
            shallow += 1
    print(f"pick plans: {count} random blocks 120-420 mm from the base, in front of the arm")
    if times_ms:
        print(f"  plan time: median {np.median(times_ms):.1f} ms, p95 {np.percentile(times_ms, 95):.1f} ms (target < 100 ms)")
        print(f"  arm motion per pick (home → lifted): median {np.median(durations):.2f} s")
    print(f"  top-down: {top_down}, shallower pitch: {shallow}, unreachable: {unreachable}")
    print(f"  worst finite-difference velocity/acceleration over limit: {worst:.6f} (must be ≤ 1)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--moves", type=int, default=500)
    parser.add_argument("--picks", type=int, default=60)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    arm = load_arm("rx200")
    rng = np.random.default_rng(args.seed)
    bench_moves(arm, rng, args.moves)
    bench_picks(arm, rng, args.picks)


if __name__ == "__main__":
    main()
