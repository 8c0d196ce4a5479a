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
from armlab.scene.random_layout import random_scene  # noqa: E402
from suction_helpers import WORKCELL, cup_pose, move_line, move_to_pose  # noqa: E402

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
    scene = random_scene(seed=SEED, n_blocks=12, n_distractors=0, workcell=WORKCELL)
    # a large block on the board in front of the arm (the helper's IK starts from the upright home pose)
    target = min((o for o in scene.objects if o.type == "block" and o.size == "large" and o.position_m[2] < 0.03),
                 key=lambda o: np.hypot(o.position_m[0], o.position_m[1] - 0.30))
    with SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, seed=SEED), scene=scene) as cell:
        cell.step(0.5)
        print(f"{WORKCELL}: UR3 + suction cup + {len(scene.objects)} blocks, physics dt {cell.model.opt.timestep * 1000:.1f} ms")
        print(f"physics real-time factor, arm sweeping (no rendering):   {physics_factor(cell):.1f}x")
        x, y, z = next(o for o in cell.truth()["objects"] if o["id"] == target.id)["position_m"]
        top, yaw = z + 0.5 * target.dimensions_m[2], target.yaw_rad
        move_to_pose(cell, cup_pose([x, y, top + 0.10]), 2.0)  # elbow up first; then only the wrist turns to the yaw
        move_to_pose(cell, cup_pose([x, y, top + 0.10], yaw_rad=yaw), 1.0)
        move_line(cell, cup_pose([x, y, top + 0.10], yaw_rad=yaw), cup_pose([x, y, top - 0.001], yaw_rad=yaw), 1.0)
        cell.gripper.grasp()
        move_line(cell, cup_pose([x, y, top - 0.001], yaw_rad=yaw), cup_pose([x, y, 0.20], yaw_rad=yaw), 1.0)
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
