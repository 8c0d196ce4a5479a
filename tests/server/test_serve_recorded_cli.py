"""`armlab serve --camera recorded --arm none` start-up refusals as a real subprocess: a recording that
cannot be played, or options that contradict each other, stop it with one line naming the file or option
(exit 2), before any server starts; the device options themselves are checked without a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

import live
from recorded_helpers import write_pairs

REPO = Path(__file__).resolve().parents[2]


def _serve(*args, tmp_path) -> subprocess.CompletedProcess:
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    return subprocess.run(
        [sys.executable, "-m", "armlab.cli", "serve", "--port", str(live.free_port()), "--db", str(tmp_path / "db.sqlite3"), *args],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=120,
    )


def test_a_depth_png_of_the_wrong_bit_depth_stops_serve_naming_it(tmp_path):
    folder = write_pairs(tmp_path / "rec")
    cv2.imwrite(str(folder / "depth_b.png"), np.zeros((48, 64), np.uint8))
    result = _serve("--camera", "recorded", "--source", str(folder), "--arm", "none", tmp_path=tmp_path)
    lines = [line for line in (result.stdout + result.stderr).splitlines() if line.strip()]
    assert result.returncode == 2 and len(lines) == 1, lines
    assert f"{folder / 'depth_b.png'}: depth must be single-channel 16-bit" in lines[0]


def _args(**given):
    import argparse

    names = ("backend", "arm", "gripper", "camera", "source", "intrinsics", "frame", "board")
    return argparse.Namespace(**{name: given.get(name) for name in names})


def test_the_device_options_choose_the_backend_and_refuse_contradictions():
    import pytest

    from armlab.cli.serve_cmd import device_choice
    from armlab.errors import ConfigError

    assert device_choice(_args())[:2] == ("sim", "interbotix_arm")
    backend, arm, gripper, camera, board = device_choice(_args(camera="recorded", source="some/folder", arm="none", frame="blocks"))
    assert (backend, arm, gripper, board) == ("real", "none", "none", "auto")
    assert camera["type"] == "recorded" and camera["source"] == "some/folder" and camera["frame"] == "blocks"
    assert device_choice(_args(camera="recorded", board="rob550"))[4] == "rob550"
    with pytest.raises(ConfigError, match=r"--arm: devices are chosen for the real backend"):
        device_choice(_args(backend="sim", arm="none"))
    with pytest.raises(ConfigError, match=r"--intrinsics: the realsense_l515 camera .* has no intrinsics"):
        device_choice(_args(camera="realsense_l515", intrinsics="k.json", arm="none"))
    with pytest.raises(ConfigError, match=r"--source: the realsense_l515 camera"):
        device_choice(_args(arm="none", source="x"))
