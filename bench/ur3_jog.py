"""Cartesian jog steps and pose moves on the simulated UR3 (issue 12 item 4), measured against the
simulation's ground truth of the suction cup (cell.truth()["gripper"]: position and orientation of the
cup body): over random start poses above the board (cup down, or tilted up to 35°), each x/y/z step of
25 mm and pitch step of 5° through the station (ik_pose planning, real servos in MuJoCo), then a pose
move without a yaw. Reports how far the cup's orientation turned and how far its point went from the
asked motion, and the planning time per step. Prints figures; asserts nothing.

    MUJOCO_GL=egl python bench/ur3_jog.py [--poses 20]
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig  # noqa: E402
from armlab.kinematics import Unreachable  # noqa: E402
from armlab.station.config import StationConfig  # noqa: E402
from armlab.station.core import Station  # noqa: E402
from armlab.store import Store  # noqa: E402
from armlab.workcell import load_workcell_arm  # noqa: E402
from armlab.workcell.loading import load_workcell_motion_config  # noqa: E402

WORKCELL = "ur3_suction"


def rotation_from_wxyz(q) -> np.ndarray:
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def angle_deg(R_a, R_b) -> float:
    return math.degrees(math.acos(np.clip((np.trace(R_a.T @ R_b) - 1.0) / 2.0, -1.0, 1.0)))


def cup(cell) -> tuple[np.ndarray, np.ndarray]:
    truth = cell.truth()["gripper"]
    return np.asarray(truth["position_m"], float), rotation_from_wxyz(truth["quat_wxyz"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=20)
    args = parser.parse_args()
    rng = np.random.default_rng(7)
    model = load_workcell_arm(WORKCELL)
    turns, offs, plan_ms, refused, heading_turns, pitch_errors = [], [], [], 0, [], []
    with SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, realtime=False, seed=1)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=model, config=StationConfig(workcell=WORKCELL),
                          store=Store(tempfile.mkdtemp() + "/bench.sqlite3"), sim=cell, synchronous=True,
                          motion_config=load_workcell_motion_config(WORKCELL))
        station.start()
        try:
            for _ in range(args.poses):
                radius, angle = rng.uniform(0.22, 0.38), rng.uniform(0.25 * math.pi, 0.75 * math.pi)
                start = [radius * math.cos(angle), radius * math.sin(angle), rng.uniform(0.10, 0.22)]
                pitch = math.pi / 2 - math.radians(rng.uniform(0.0, 35.0))
                try:
                    station.move_to(start, pitch_rad=pitch, yaw_rad=float(rng.uniform(-math.pi, math.pi)), wait=True)
                except Unreachable:
                    continue
                for axis, amount in (("x", 0.025), ("y", -0.025), ("z", 0.025), ("pitch", math.radians(5.0))):
                    p0, R0 = cup(cell)
                    t = time.perf_counter()
                    try:
                        station.step_gripper(axis, amount, wait=True)
                    except Unreachable:
                        refused += 1
                        continue
                    plan_ms.append((time.perf_counter() - t) * 1000)  # plan + simulated motion (fast mode)
                    p1, R1 = cup(cell)
                    if axis == "pitch":
                        offs.append(np.linalg.norm(p1 - p0) * 1000)
                        pitch_errors.append(abs(angle_deg(R0, R1) - 5.0))
                    else:
                        asked = np.zeros(3)
                        asked["xyz".index(axis)] = amount
                        offs.append(np.linalg.norm(p1 - p0 - asked) * 1000)
                        turns.append(angle_deg(R0, R1))
                try:  # pointing straight down at some heading, then a pose move with neither pitch nor yaw
                    station.move_to(start, pitch_rad=math.pi / 2, yaw_rad=float(rng.uniform(-math.pi, math.pi)), wait=True)
                    _p0, R0 = cup(cell)
                    station.move_to([start[0] - 0.05, start[1] + 0.03, start[2]], wait=True)
                except Unreachable:
                    continue
                _p1, R1 = cup(cell)
                heading_turns.append(angle_deg(R0, R1))  # down both times: any turn is the heading
        finally:
            station.close()
    print(f"UR3 jog steps measured by the simulation's cup pose ({len(turns)} linear steps of 25 mm, "
          f"{len(pitch_errors)} pitch steps of 5 deg, {refused} refused)")
    print(f"  linear steps: cup orientation turned mean {statistics.mean(turns):.3f} deg, max {max(turns):.3f} deg")
    print(f"  all steps: cup point off the asked motion mean {statistics.mean(offs):.2f} mm, max {max(offs):.2f} mm")
    print(f"  pitch steps: rotation off 5 deg by mean {statistics.mean(pitch_errors):.3f} deg, max {max(pitch_errors):.3f} deg")
    print(f"  step time (plan + fast-mode motion): median {statistics.median(plan_ms):.0f} ms, max {max(plan_ms):.0f} ms")
    print(f"  pose moves without pitch or yaw (cup down before and after): cup turned mean "
          f"{statistics.mean(heading_turns):.2f} deg, max {max(heading_turns):.2f} deg")


if __name__ == "__main__":
    main()
