"""UR3 suction workcell simulation benchmark (issue 12): physics real-time factor (UR3 + cup + 12 blocks, arm
sweeping, no rendering), the same while the cup carries a block under vacuum, render time at 1280x720,
the fast-mode loop while rendering at 30 fps, and real-time mode's pacing. Prints figures; asserts nothing.

    MUJOCO_GL=egl python bench/sim_ur3.py
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "devices" / "sim"))

import numpy as np  # noqa: E402

from armlab.devices.arm import JointTrajectory  # noqa: E402
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig  # noqa: E402
from armlab.scene import Scene, random_scene  # noqa: E402
from suction_helpers import WORKCELL, block_scene, cup_pose, move_line, move_to_pose  # noqa: E402

SEED = 3
SWEEP_RAD = np.array([0.6, 0.2, 0.2, 0.3, 0.3, 0.8])


def sweep(q0: np.ndarray, duration_s: float) -> JointTrajectory:
    times = np.linspace(0.0, duration_s, int(duration_s * 100) + 1)
    return JointTrajectory(times, q0 + np.sin(2 * np.pi * times / duration_s)[:, None] * SWEEP_RAD)


def physics_factor(cell: SimWorkcell, sim_seconds: float = 5.0) -> float:
    q0 = cell.arm.read_joint_state().position_rad
    cell.arm.command_trajectory(sweep(q0, sim_seconds))
    start = time.perf_counter()
    cell.step(sim_seconds)
    return sim_seconds / (time.perf_counter() - start)


def main() -> None:  # noqa: D103
    scene = random_scene(seed=SEED, n_blocks=12, n_distractors=0)
    carry = block_scene(0.0, 0.30, block_id="held")
    scene = Scene(objects=[*scene.objects, *[o for o in carry.objects]]) if not scene.overlapping_pairs() else scene
    with SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, seed=SEED), scene=scene) as cell:
        cell.step(0.5)
        start = cell.arm.read_joint_state().position_rad
        print(f"{WORKCELL}: UR3 + suction cup + {len(scene.objects)} blocks, physics dt {cell.model.opt.timestep * 1000:.1f} ms")
        print(f"physics real-time factor, arm sweeping (no rendering):   {physics_factor(cell):.1f}x")
        move_to_pose(cell, cup_pose([0.0, 0.30, 0.138]), 2.0)
        move_line(cell, cup_pose([0.0, 0.30, 0.138]), cup_pose([0.0, 0.30, 0.037]), 1.0)
        cell.gripper.grasp()
        move_line(cell, cup_pose([0.0, 0.30, 0.037]), cup_pose([0.0, 0.30, 0.20]), 1.0)
        held = cell.gripper.read_state().holding
        print(f"physics real-time factor, carrying a block (held={held}):  {physics_factor(cell):.1f}x")
        cell.render()
        times = []
        for _ in range(30):
            t = time.perf_counter()
            cell.render_raw()
            times.append((time.perf_counter() - t) * 1000)
        print(f"render colour+depth 1280x720: median {statistics.median(times):.1f} ms, p90 {np.percentile(times, 90):.1f} ms")
        cell.arm.command_trajectory(sweep(cell.arm.read_joint_state().position_rad, 3.0))
        t, end_s = time.perf_counter(), cell.sim_time_s + 3.0
        while cell.sim_time_s < end_s:
            cell.camera.read()
        print(f"fast-mode loop with 30 fps rendering: {3.0 / (time.perf_counter() - t):.2f}x real time")
        del start
    with SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, realtime=True, seed=SEED), scene=scene) as cell:
        cell.camera.async_read(timeout_ms=5000)
        cell.arm.command_trajectory(sweep(cell.arm.read_joint_state().position_rad, 3.0))
        first = cell.camera.read_latest(max_age_ms=5000).sequence
        wall0, sim0 = time.monotonic(), cell.sim_time_s
        time.sleep(3.0)
        factor = (cell.sim_time_s - sim0) / (time.monotonic() - wall0)
        fps = (cell.camera.read_latest(max_age_ms=5000).sequence - first) / (time.monotonic() - wall0)
    print(f"real-time mode (physics + camera threads): {factor:.2f}x wall clock, camera {fps:.1f} fps")


if __name__ == "__main__":
    main()
