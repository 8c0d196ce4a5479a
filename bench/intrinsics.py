"""Intrinsics from the checkerboard capture, measured against the simulated camera's TRUE intrinsics
(read from the frustum MuJoCo draws the camera with): fx/fy/cx/cy error and RMS by number of views,
over several rigs (camera pose seeds); the capture's per-view and solve time; and the extrinsic
calibration's camera position error with the measured intrinsics vs with the true ones.

    MUJOCO_GL=egl .venv/bin/python bench/intrinsics.py [--rigs 4] [--views 6 10 15 20]

Views are the sim's noisy colour frames of the config/intrinsics.yaml board placed at seeded poses
(armlab.devices.sim.checkerboard.calibration_poses); refused views (not found, blurry, duplicate) are
counted and skipped, as the page's capture would.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from dataclasses import replace

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np  # noqa: E402

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig  # noqa: E402
from armlab.devices.sim.checkerboard import calibration_poses, pose_in_camera_frame  # noqa: E402
from armlab.vision import calibrate_extrinsics, load_perception_config  # noqa: E402
from armlab.vision.intrinsics_capture import (  # noqa: E402
    IntrinsicsCapture,
    IntrinsicsRejected,
    load_intrinsics_config,
    solve_intrinsics,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rigs", type=int, default=4)
    parser.add_argument("--views", type=int, nargs="+", default=[6, 10, 15, 20])
    args = parser.parse_args()
    config = load_intrinsics_config()
    perception = load_perception_config()
    most = max(args.views)
    rows: dict[int, list[dict]] = {n: [] for n in args.views}
    add_ms, solve_ms, refused, position_errors = [], {n: [] for n in args.views}, {}, {"measured": [], "true": []}
    for rig in range(args.rigs):
        cell = SimWorkcell(SimWorkcellConfig(seed=100 + rig))
        cell.start()
        try:
            truth = cell.camera_intrinsics()
            T_world_camera = np.asarray(cell.truth()["camera"]["T_world_camera"])
            capture = IntrinsicsCapture(config, (1280, 720))
            for position_m, rotvec in calibration_poses(most + 4, seed=rig):
                if len(capture.views) >= most:
                    break
                cell.place_checkerboard(*pose_in_camera_frame(T_world_camera, position_m, rotvec))
                frame = cell.render()
                started = time.perf_counter()
                try:
                    capture.add(frame.color_bgr)
                except IntrinsicsRejected as error:
                    refused[error.code] = refused.get(error.code, 0) + 1
                add_ms.append((time.perf_counter() - started) * 1000)
            cell.place_checkerboard()
            board_frame = cell.render()
            for n in args.views:
                views = capture.views[:n]
                started = time.perf_counter()
                result = solve_intrinsics([v.corners_px for v in views], config.target, (1280, 720), config.capture.fix_aspect_ratio)
                solve_ms[n].append((time.perf_counter() - started) * 1000)
                measured = {"fx": result.K[0, 0], "fy": result.K[1, 1], "cx": result.K[0, 2], "cy": result.K[1, 2]}
                rows[n].append({**{k: abs(measured[k] - truth[k]) for k in measured}, "rms": result.rms})
                if n == most:
                    for label, intrinsics in (("measured", result.to_intrinsics()),
                                              ("true", replace(result.to_intrinsics(), dist=(0.0,) * 5, **truth))):
                        calibration = calibrate_extrinsics(board_frame.color_bgr, intrinsics, perception, board_frame.depth_mm)
                        position_errors[label].append(1000 * float(np.linalg.norm(calibration.camera_position_m - T_world_camera[:3, 3])))
        finally:
            cell.close()
    print(f"intrinsics vs MuJoCo's true camera ({args.rigs} rigs; noisy sim colour frames, 1280x720, f = 904 px)")
    print(f"{'views':>5} {'|dfx| px':>16} {'|dfy| px':>16} {'|dcx| px':>16} {'|dcy| px':>16} {'RMS px':>8} {'solve ms':>9}")
    for n in args.views:
        cols = [f"{statistics.mean(r[k] for r in rows[n]):6.2f} (max {max(r[k] for r in rows[n]):5.2f})" for k in ("fx", "fy", "cx", "cy")]
        print(f"{n:>5} " + " ".join(f"{c:>16}" for c in cols)
              + f" {statistics.mean(r['rms'] for r in rows[n]):8.3f} {statistics.median(solve_ms[n]):9.1f}")
    print(f"per captured view (find + blur + duplicate + coverage): median {statistics.median(add_ms):.1f} ms, "
          f"max {max(add_ms):.1f} ms; refused views: {refused or 'none'}")
    for label, errors in position_errors.items():
        print(f"extrinsic calibration with the {label} intrinsics ({most} views): camera position error "
              f"mean {statistics.mean(errors):.2f} mm, max {max(errors):.2f} mm")


if __name__ == "__main__":
    main()
