"""`armlab calibrate-points` in a subprocess: 4 clicked pixels of a simulated view with their world
points give the true camera pose; too few or collinear points are a clear error and write nothing."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.vision.geometry import project_points

REPO = Path(__file__).resolve().parents[2]


def _armlab(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "armlab.cli", *args], capture_output=True, text=True, timeout=120, cwd=REPO)


def test_calibrate_points_command(tmp_path):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=8, camera_pose_error=True))
    cell.start()
    try:
        truth = cell.truth()["camera"]
    finally:
        cell.close()
    T_true = np.asarray(truth["T_world_camera"])
    world = [(x, y) for y in (-0.125, 0.425) for x in (-0.4, 0.4)]
    pixels = np.round(project_points(T_true, np.asarray(truth["K"]), np.asarray(truth["dist"]), np.array([[x, y, 0.0] for x, y in world])))
    args = [arg for (u, v), (x, y) in zip(pixels, world) for arg in ("--point", f"{u},{v},{x},{y}")]
    out = _armlab("calibrate-points", *args, "--out", str(tmp_path / "cal.json"))
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert np.linalg.norm(np.asarray(result["calibration"]["camera_position_m"]) - T_true[:3, 3]) < 0.005
    assert result["fit"]["points"] == 4 and result["fit"]["reprojection_error_px"] < 0.6
    assert json.loads((tmp_path / "cal.json").read_text())["T_world_camera"] == result["calibration"]["T_world_camera"]
    few = _armlab("calibrate-points", *args[:6], "--out", str(tmp_path / "few.json"))
    assert few.returncode == 2 and "at least 4 points" in few.stderr and not (tmp_path / "few.json").exists()
    line = [arg for i in range(4) for arg in ("--point", f"{100 + 50 * i},{200 + 10 * i},{-0.3 + 0.2 * i},0.1")]
    collinear = _armlab("calibrate-points", *line, "--out", str(tmp_path / "line.json"))
    assert collinear.returncode == 2 and "collinear" in collinear.stderr
