"""Simulation benchmark: physics real-time factor (arm + 12 blocks, no rendering; target >= 20x),
colour+depth render time at 1280x720 (target <= 33 ms per frame pair), the real-time factor of the
whole fast-mode loop while rendering at 30 fps, and real-time mode's pacing and camera rate.
Prints figures; asserts nothing.

    MUJOCO_GL=egl python bench/sim.py
"""

from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from armlab.devices.arm import JointTrajectory  # noqa: E402
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig  # noqa: E402
from armlab.scene.random_layout import random_scene  # noqa: E402

SEED = 3


def moving_trajectory(q0: np.ndarray, duration_s: float) -> JointTrajectory:
    """A slow sweep of all joints so the servos and contacts work during the measurement."""
    times = np.linspace(0.0, duration_s, int(duration_s * 100) + 1)
    sweep = np.sin(2 * np.pi * times / duration_s)[:, None] * np.array([0.6, 0.2, 0.2, 0.3, 0.8])
    return JointTrajectory(times, q0 + sweep)


def bench_physics(cell: SimWorkcell, sim_seconds: float = 5.0) -> float:
    q0 = np.array([0.0, -0.6, 0.6, 1.0, 0.0])
    cell.arm.command_trajectory(JointTrajectory(np.array([0.0, 0.5]), np.array([cell.arm.read_joint_state().position_rad, q0])), wait=True)
    cell.arm.command_trajectory(moving_trajectory(q0, sim_seconds))
    start = time.perf_counter()
    cell.step(sim_seconds)
    return sim_seconds / (time.perf_counter() - start)


def bench_render(cell: SimWorkcell, frames: int = 40) -> dict[str, float]:
    cell.render()  # warm up
    raw_ms, frame_ms = [], []
    for _ in range(frames):
        start = time.perf_counter()
        cell.render_raw()
        raw_ms.append((time.perf_counter() - start) * 1000)
        start = time.perf_counter()
        cell.render()
        frame_ms.append((time.perf_counter() - start) * 1000)
    return {"raw_median_ms": statistics.median(raw_ms), "raw_p90_ms": float(np.percentile(raw_ms, 90)),
            "frame_median_ms": statistics.median(frame_ms), "frame_p90_ms": float(np.percentile(frame_ms, 90))}


def bench_loop(cell: SimWorkcell, sim_seconds: float = 3.0) -> float:
    q0 = cell.arm.read_joint_state().position_rad
    cell.arm.command_trajectory(moving_trajectory(q0, sim_seconds))
    start = time.perf_counter()
    end_s = cell.sim_time_s + sim_seconds
    while cell.sim_time_s < end_s:
        cell.camera.read()  # advances the physics to the next 30 fps frame and renders it
    return sim_seconds / (time.perf_counter() - start)


def bench_realtime(scene, seconds: float = 3.0) -> tuple[float, float]:
    """Real-time mode (physics thread + 30 fps camera thread): (real-time factor, frames per second)."""
    with SimWorkcell(SimWorkcellConfig(realtime=True, seed=SEED, camera_fps=30.0), scene=scene) as cell:
        cell.camera.async_read(timeout_ms=5000)
        q0 = np.array([0.0, -0.6, 0.6, 1.0, 0.0])
        start = cell.arm.read_joint_state().position_rad
        cell.arm.command_trajectory(JointTrajectory(np.array([0.0, 1.0]), np.array([start, q0])), wait=True)
        cell.arm.command_trajectory(moving_trajectory(q0, seconds))
        first = cell.camera.read_latest(max_age_ms=5000).sequence
        wall0, sim0 = time.monotonic(), cell.sim_time_s
        time.sleep(seconds)
        factor = (cell.sim_time_s - sim0) / (time.monotonic() - wall0)
        fps = (cell.camera.read_latest(max_age_ms=5000).sequence - first) / (time.monotonic() - wall0)
    return factor, fps


def main() -> None:  # noqa: D103
    scene = random_scene(seed=SEED, n_blocks=12, n_distractors=0)
    config = SimWorkcellConfig(realtime=False, seed=SEED)
    with SimWorkcell(config, scene=scene) as cell:
        cell.step(0.5)
        print(f"seed {SEED}: arm + {len(scene.objects)} blocks, physics dt {cell.model.opt.timestep * 1000:.1f} ms", flush=True)
        physics = bench_physics(cell)
        print(f"physics real-time factor (no rendering): {physics:.1f}x   (target >= 20x)", flush=True)
        render = bench_render(cell)
        print(f"render colour+depth 1280x720, one pass:   median {render['raw_median_ms']:.1f} ms, "
              f"p90 {render['raw_p90_ms']:.1f} ms   (target <= 33 ms)")
        print(f"  + noise, BGR, uint16 mm (camera frame): median {render['frame_median_ms']:.1f} ms, "
              f"p90 {render['frame_p90_ms']:.1f} ms", flush=True)
        loop = bench_loop(cell)
        print(f"whole loop with 30 fps rendering:         {loop:.2f}x real time (fast mode: physics + every frame)", flush=True)
    factor, fps = bench_realtime(scene)
    print(f"real-time mode (physics + camera threads): {factor:.2f}x wall clock, camera {fps:.1f} fps (target 30)")


if __name__ == "__main__":
    main()
