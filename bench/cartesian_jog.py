"""Released Cartesian hold-to-run jogs (issue 21): stopping distance of the gripper point, measured on the simulation.

    .venv/bin/python bench/cartesian_jog.py [--held-s 1.0] [--beat-s 0.05]

A fast, synchronous simulated RX200 station (physics advances only in this script's steps, so wall-clock load does
not enter the distances): the gripper pointing straight down over the board, a Cartesian jog along +x, -y and +z at
25 / 50 / 100 % of jog_max_speed_m_s, held with heartbeats every --beat-s of sim time for --held-s, then released
(no more heartbeats). From the true gripper point at every physics step: the distance along the axis from the last
heartbeat to rest against the deadman's bound v*(jog_hold_s + one control period) + v^2/(2 jog_accel_m_s2), the
time to rest, the largest distance off the line and the pitch and yaw change over the whole jog; and the wall time
of one heartbeat's re-plan (IK of the line, the station's checks; the only wall-clock figure, the median). A jog that
reaches a place its line cannot pass while still held stops before it (the station's event says why; printed).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

START_M = [0.0, 0.25, 0.12]
CASES = [("x", 1), ("y", -1), ("z", 1)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--held-s", type=float, default=1.0, help="sim seconds of heartbeats before the release")
    parser.add_argument("--beat-s", type=float, default=0.05, help="sim seconds between heartbeats")
    args = parser.parse_args()

    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.devices.sim.config import load_sim_config
    from armlab.kinematics import load_arm
    from armlab.motion.gripper_step import angle_difference_rad, gripper_pose
    from armlab.station import Station, StationConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=0))
    cell.start()
    model = load_arm("rx200")
    database = Path(tempfile.mkdtemp()) / "bench.sqlite3"
    station = Station(cell.arm, cell.gripper, cell.camera, model=model, config=StationConfig(database_path=str(database)),
                      sim=cell, backend="sim", synchronous=True)
    station.start()
    config = station.motion_config
    physics = load_sim_config().physics
    period_s = physics.control_period_s
    print(f"Cartesian jog released after {args.held_s:.1f} s of heartbeats every {args.beat_s * 1000:.0f} ms (sim time); "
          f"top {config.jog_max_speed_m_s:.3f} m/s, ramp {config.jog_accel_m_s2:.2f} m/s^2, hold {config.jog_hold_s:.2f} s, "
          f"control period {period_s * 1000:.0f} ms")
    print(f"{'jog':>5} {'%':>4} {'v m/s':>6} {'stop mm':>8} {'bound mm':>9} {'to rest s':>9} {'off line mm':>11} "
          f"{'pitch deg':>9} {'yaw deg':>8} {'re-plan ms':>10}")
    try:
        for percent in (25, 50, 100):
            for axis, sign in CASES:
                q_start = station.solve_pose(START_M, pitch_rad=math.pi / 2, yaw_rad=0.0)
                station.move_joints(q_start, wait=True)
                station.wait_motion(5.0)
                cell.step(0.3)
                q0 = np.asarray(cell.arm.read_joint_state().position_rad, float)
                start = cell.gripper_point_m()
                seen = station.events.last_seq
                cell.start_path_recording(period_s=physics.timestep_s)
                station.jog_cartesian(axis, sign * config.jog_max_speed_m_s, source="bench", speed_percent=percent)
                replans = []
                for _ in range(int(args.held_s / args.beat_s)):
                    cell.step(args.beat_s)
                    began = time.perf_counter()
                    assert station.heartbeat(source="bench"), "the jog ended while heartbeats arrived"
                    replans.append(time.perf_counter() - began)
                released_s = cell.sim_time_s
                cell.step(1.0)
                path = cell.stop_path_recording()
                q1 = np.asarray(cell.arm.read_joint_state().position_rad, float)
                direction = np.zeros(3)
                direction["xyz".index(axis)] = sign
                along = (path[:, 1:] - start) @ direction
                off = np.linalg.norm((path[:, 1:] - start) - along[:, None] * direction[None, :], axis=1).max()
                at_release = int(np.searchsorted(path[:, 0], released_s))
                moving = np.flatnonzero(np.abs(np.diff(along)) > 1e-6)
                rest_s = path[moving[-1] + 1, 0] - released_s if moving.size else 0.0
                stop_m = along[-1] - along[at_release]
                v = config.jog_max_speed_m_s * percent / 100
                bound_m = v * (config.jog_hold_s + period_s) + v * v / (2 * config.jog_accel_m_s2)
                p0, p1 = gripper_pose(model, q0), gripper_pose(model, q1)
                print(f"{axis}{'+' if sign > 0 else '-':<4} {percent:>4} {v:>6.3f} {stop_m * 1000:>8.1f} {bound_m * 1000:>9.1f} "
                      f"{rest_s:>9.3f} {off * 1000:>11.2f} {math.degrees(angle_difference_rad(p1.pitch_rad, p0.pitch_rad)):>9.2f} "
                      f"{math.degrees(angle_difference_rad(p1.yaw_rad, p0.yaw_rad)):>8.2f} {1000 * float(np.median(replans)):>10.1f}")
                for event in station.events.since(seen):
                    if "stops short" in event["message"]:
                        print(f"      ({event['message']}: held against the boundary, it stopped before it)")
    finally:
        station.close()
        cell.close()


if __name__ == "__main__":
    main()
