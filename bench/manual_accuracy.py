"""Manual operation accuracy in the fast simulation (issue 9 items 1 and 2), against ground truth.

    .venv/bin/python bench/manual_accuracy.py [--poses 40] [--spots 12] [--seed 0]

Jog steps: from random reachable start poses (gripper point over the board, pitch 20-90°, any yaw),
every axis ± (10 mm; 0.1 rad of pitch; 0.2 rad of roll) through Station.step_gripper; for each
accepted step, FK of the measured joints before and after gives the error along the axis, the largest
motion off it and the pitch and yaw change; refused steps are counted by reason.
Click under the arm: for random board spots (bare, or a block's top), the arm is put on the true camera
ray of the spot 120 mm up and the spot's pixel is sent to pixel-to-world; the error against the spot,
and the same with the newest frame's raw depth (what the click used before).
"""

from __future__ import annotations

import argparse
import collections
import math
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402


def _pose(arm, q):
    T = arm.fk(np.asarray(q, float))
    approach, closing, p = T[:3, 0], T[:3, 1], T[:3, 3]
    radial = p[:2] / max(np.linalg.norm(p[:2]), 1e-9)
    return p, math.atan2(-approach[2], float(approach[:2] @ radial)), math.atan2(closing[1], closing[0])


def bench_steps(station, arm, poses: int, rng) -> None:
    from armlab.kinematics import Unreachable

    steps = [(a, s * 0.01) for a in "xyz" for s in (1, -1)] + [("pitch", 0.1), ("pitch", -0.1), ("roll", 0.2), ("roll", -0.2)]
    along, off, pitch_err, yaw_err, refused, accepted = [], [], [], [], collections.Counter(), 0
    made = 0
    while made < poses:
        target = [rng.uniform(-0.3, 0.3), rng.uniform(0.05, 0.35), rng.uniform(0.04, 0.25)]
        try:
            q0 = arm.ik(target, pitch=rng.uniform(math.radians(20), math.pi / 2), yaw=rng.uniform(-math.pi, math.pi))
        except Unreachable:
            continue
        made += 1
        for axis, amount in steps:
            station.move_joints(q0, wait=True)
            p0, pitch0, yaw0 = _pose(arm, station.joints_rad())
            try:
                station.step_gripper(axis, amount, wait=True)
            except ValueError as error:
                refused[getattr(error, "reason", type(error).__name__)] += 1
                continue
            accepted += 1
            p1, pitch1, yaw1 = _pose(arm, station.joints_rad())
            d = p1 - p0
            if axis in "xyz":
                k = "xyz".index(axis)
                along.append(abs(d[k] - amount))
                off.append(float(np.abs(np.delete(d, k)).max()))
                pitch_err.append(abs(math.remainder(pitch1 - pitch0, 2 * math.pi)))
                yaw_err.append(abs(math.remainder(yaw1 - yaw0, 2 * math.pi)))
            else:
                off.append(float(np.linalg.norm(d)))
                pitch_err.append(abs(math.remainder(pitch1 - pitch0 - (amount if axis == "pitch" else 0.0), 2 * math.pi)))
    total = poses * len(steps)
    print(f"jog steps: {poses} start poses x {len(steps)} steps = {total}: accepted {accepted}, refused {total - accepted} {dict(refused)}")
    print(f"  along the axis: max {max(along) * 1000:.2f} mm, mean {np.mean(along) * 1000:.2f} mm (target <= 1 mm)")
    print(f"  off the asked motion: max {max(off) * 1000:.2f} mm (target <= 1 mm)")
    print(f"  pitch kept (or changed by the step): max error {math.degrees(max(pitch_err)):.3f} deg (target <= 0.5 deg)")
    print(f"  yaw kept: max change {math.degrees(max(yaw_err)):.3f} deg (target <= 0.5 deg)")


def bench_clicks(station, spots: int, rng) -> None:
    from armlab.skills.perceive import pixel_to_world
    from armlab.vision.geometry import backproject, transform_points
    from armlab.vision.pixel_world import world_to_pixel

    truth = station.sim.truth()
    camera = np.asarray(truth["camera"]["T_world_camera"], float)[:3, 3]
    tops = [np.asarray(o["position_m"], float) * [1, 1, 2] for o in truth["objects"]]  # on the board: top = 2 x centre z
    errors, raw_errors, sources = [], [], collections.Counter()
    cal = station.calibration
    for index in range(spots):
        spot = tops[index % len(tops)] if index % 3 == 0 else np.array([rng.uniform(-0.3, 0.3), rng.uniform(0.0, 0.35), 0.0])
        station.home(wait=True)
        station.fresh_perception()
        t = (0.12 - spot[2]) / (camera[2] - spot[2])
        try:
            station.move_to(spot + t * (camera - spot), pitch_rad=math.pi / 2, wait=True)
        except ValueError:
            continue
        station.fresh_perception()
        uv = world_to_pixel(cal, spot[None, :])[0]
        result = pixel_to_world(station, *uv)
        sources[result["on"]] += 1
        errors.append(float(np.linalg.norm(np.asarray(result["position_m"]) - spot)))
        frame, _ = station.frames.get()
        depth_m = frame.depth_mm[int(round(uv[1])), int(round(uv[0]))] / 1000.0
        raw = transform_points(cal.T_world_camera, backproject(np.array([uv]), np.array([depth_m]), cal.K, cal.dist))[0]
        raw_errors.append(float(np.linalg.norm(raw - spot)))
    print(f"click under the arm: {len(errors)} spots ({dict(sources)})")
    print(f"  pixel-to-world error: max {max(errors) * 1000:.1f} mm, mean {np.mean(errors) * 1000:.1f} mm")
    print(f"  the raw depth there (the old click): max {max(raw_errors) * 1000:.1f} mm, mean {np.mean(raw_errors) * 1000:.1f} mm")


def main(argv: list[str] | None = None) -> int:
    from armlab import skills
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.scene import Scene
    from armlab.station.config import StationConfig
    from armlab.station.core import Station
    from armlab.store import Store

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=40)
    parser.add_argument("--spots", type=int, default=12)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    scene = Scene.from_dict({"objects": [
        {"id": "a", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.3},
        {"id": "b", "type": "block", "color": "blue", "size": "small", "position_m": [-0.15, 0.28, 0.0125], "yaw_rad": 0.0},
    ]})
    arm = load_arm("rx200")
    with tempfile.TemporaryDirectory() as tmp, SimWorkcell(SimWorkcellConfig(realtime=False, seed=args.seed), scene=scene) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=arm, config=StationConfig(),
                          store=Store(Path(tmp) / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        try:
            job = skills.calibrate(station)
            if not (job.wait(60) and job.state == "succeeded"):
                print(f"calibration failed: {job.message}")
                return 1
            bench_clicks(station, args.spots, rng)
            bench_steps(station, arm, args.poses, rng)
        finally:
            station.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
