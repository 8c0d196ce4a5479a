"""The closed loop after a place (issue 19 item 4, armlab.tasks.place_check) on the real arm in the simulation: per
rig (seed), the camera calibrated from the board tags and the arm from the camera, one block is carried round
`--spots` board spots twice by a job's runner; MuJoCo truth after every place gives the block's distance from its
target. The first round is what the arm calibration leaves (the "after arm calibration" figure of
bench/arm_accuracy.py, measured at the block); the second, with the place check on, is "after the closed loop at
the block" (each place shifted by what the look after the first place there saw remain); with --off, the second
round without it (the same arm, uncorrected). Prints figures; asserts nothing.

    MUJOCO_GL=egl .venv/bin/python bench/place_loop.py [--seeds 0 1 2] [--spots 3] [--realism real] [--off]
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

SPOTS_M = ((0.17, 0.11), (0.05, 0.25), (-0.15, 0.20), (-0.20, 0.08), (0.22, 0.20))
EDGE_M = 0.038


def rig(seed: int, spots: list, realism: str, loop: bool, folder: str) -> list[tuple[int, float, float]]:
    """[(spot, truth error mm, check's measured residual mm or nan)] for 2 rounds of the spots."""
    from armlab import skills
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.scene import Scene
    from armlab.station import Station, StationConfig
    from armlab.store import Store
    from armlab.tasks.policy import Move, Plan
    from armlab.tasks.runner import TaskRunner
    from armlab.workcell import load_workcell_arm

    scene = Scene.from_dict({"objects": [{"id": "b", "type": "block", "color": "red", "size": "large",
                                          "position_m": [*spots[-1], EDGE_M / 2], "yaw_rad": 0.0}]})
    out: list = []
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed, realism=realism), scene=scene) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(), config=StationConfig(),
                          store=Store(Path(folder) / f"p{seed}.sqlite3"), sim=cell, synchronous=True)
        station.start()
        for calibrate in (skills.calibrate, skills.calibrate_arm):
            job = calibrate(station)
            assert job.wait(900) and job.state == "succeeded", job.message
        moves = 2 * len(spots)

        def run(ctx):
            runner = TaskRunner(station, ctx, "place loop")
            runner.place_check.enabled = True  # the first round measures (whatever the station's config says)

            def policy(objects, _given_up) -> Plan:
                blocks = [o for o in objects if o.is_cube]
                if len(out) >= moves or not blocks:
                    return Plan([], done=len(out), left=0, finished=True)
                spot = len(out) % len(spots)
                if len(out) == len(spots):
                    runner.place_check.enabled = loop  # the second round: with the loop, or without (--off)

                def measured(_edge, spot=spot):
                    truth = next(o for o in cell.truth()["objects"] if o["id"] == "b")["position_m"]
                    out.append((spot, 1000.0 * math.dist(truth[:2], spots[spot])))

                return Plan([Move(blocks[0], (*spots[spot], 0.0), "bench", on_placed=measured)], done=len(out), left=moves - len(out))

            return runner.run(policy)

        job = station.start_job("auto", "place loop", run)
        assert job.wait(1800) and job.state == "succeeded", job.message
        records = job.result["place_check"]["records"]
        station.close()
    return out, records


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--spots", type=int, default=3)
    parser.add_argument("--realism", choices=("real", "camera", "ideal"), default="real")
    parser.add_argument("--off", action="store_true", help="the second round without the loop")
    args = parser.parse_args(argv)
    spots = list(SPOTS_M[: args.spots])
    second = "without the loop (--off)" if args.off else "after the closed loop at the block"
    print(f"place accuracy at the block, realism {args.realism}: {len(spots)} spots x 2 rounds, MuJoCo truth (mm)")
    firsts, seconds = [], []
    with tempfile.TemporaryDirectory() as folder:
        for seed in args.seeds:
            start = time.perf_counter()
            errors, records = rig(seed, spots, args.realism, not args.off, folder)
            first = [e for i, (_, e) in enumerate(errors) if i < len(spots)]
            again = [e for i, (_, e) in enumerate(errors) if i >= len(spots)]
            firsts += first
            seconds += again
            seen = [r.get("residual_mm") for r in records]
            print(f"rig seed {seed}: after arm calibration mean {np.mean(first):.2f} max {np.max(first):.2f}; {second} "
                  f"mean {np.mean(again):.2f} max {np.max(again):.2f}; per spot {[round(e, 2) for e in first]} -> "
                  f"{[round(e, 2) for e in again]}; the looks measured {seen} ({time.perf_counter() - start:.0f} s wall)", flush=True)
    print(f"over rigs: after arm calibration mean {np.mean(firsts):.2f} mm, max {np.max(firsts):.2f} mm; {second} mean "
          f"{np.mean(seconds):.2f} mm, max {np.max(seconds):.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
