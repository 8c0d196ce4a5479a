"""The perception CLI end to end in a subprocess: tags, intrinsics, extrinsics, detect; bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

from armlab.vision.evaluate import expected_tops

REPO = Path(__file__).resolve().parents[2]
CHESSBOARD = Path(__file__).parent / "data" / "chessboard"


def _armlab(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "armlab.cli", *args], capture_output=True, text=True, timeout=120, cwd=REPO)


def test_tags_command(tmp_path, board_frame):
    path = tmp_path / "board.png"
    cv2.imwrite(str(path), board_frame[0])
    out = _armlab("tags", str(path))
    assert out.returncode == 0, out.stderr
    tags = json.loads(out.stdout)
    assert [t["id"] for t in tags] == [1, 2, 3, 4]
    assert np.array(tags[0]["corners_px"]).shape == (4, 2)
    assert json.loads(_armlab("tags", str(path), "--dict", "DICT_4X4_50").stdout) == []
    bad = _armlab("tags", str(tmp_path / "missing.png"))
    assert bad.returncode == 2 and "cannot read image" in bad.stderr


def test_calibrate_intrinsics_command():
    images = [str(p) for p in sorted(CHESSBOARD.glob("left*.jpg"))]
    out = _armlab("calibrate-intrinsics", *images, "--pattern", "9x6", "--square", "0.025")
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert np.array(result["K"]).shape == (3, 3) and len(result["dist"]) == 5
    assert result["K"][0][0] == __import__("pytest").approx(535.9, abs=3.0)
    assert 0.3 < result["rms"] < 0.5
    bad = _armlab("calibrate-intrinsics", images[0], "--pattern", "9-6")
    assert bad.returncode == 2 and "9x6" in bad.stderr


def test_extrinsics_then_detect_on_a_sim_frame(tmp_path, event_frame):
    frame, truth = event_frame
    color, depth, cal_path = tmp_path / "color.png", tmp_path / "depth.png", tmp_path / "cal.json"
    cv2.imwrite(str(color), frame.color_bgr)
    cv2.imwrite(str(depth), frame.depth_mm)
    out = _armlab("calibrate-extrinsics", str(color), "--depth", str(depth), "--out", str(cal_path))
    assert out.returncode == 0, out.stderr
    cal = json.loads(cal_path.read_text())
    true_position = np.asarray(truth["camera"]["T_world_camera"])[:3, 3]
    assert np.linalg.norm(np.array(cal["camera_position_m"]) - true_position) < 0.003
    assert cal["depth_check_error_m"] < 0.003
    out = _armlab("detect", str(color), "--depth", str(depth), "--calibration", str(cal_path))
    assert out.returncode == 0, out.stderr
    blocks = json.loads(out.stdout)
    assert set(blocks[0]) == {"color", "size", "position_m", "yaw_rad", "stack_level"}
    tops = [t for t in expected_tops(truth) if t.type == "block"]
    assert len(blocks) == len(tops)
    for top in tops:
        match = min(blocks, key=lambda b: np.linalg.norm(np.array(b["position_m"]) - top.top_center_m))
        assert np.linalg.norm(np.array(match["position_m"]) - top.top_center_m) < 0.005
        assert (match["color"], match["size"], match["stack_level"]) == (top.color, top.size, top.stack_level)


def test_extrinsics_refuses_a_frame_without_tags(tmp_path):
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((720, 1280, 3), 120, np.uint8))
    out = _armlab("calibrate-extrinsics", str(blank), "--out", str(tmp_path / "cal.json"))
    assert out.returncode == 2 and "board tags" in out.stderr
    assert not (tmp_path / "cal.json").exists()
    small = tmp_path / "small.png"
    cv2.imwrite(str(small), np.full((480, 640, 3), 120, np.uint8))
    out = _armlab("calibrate-extrinsics", str(small), "--out", str(tmp_path / "cal.json"))
    assert out.returncode == 2 and "640x480" in out.stderr
