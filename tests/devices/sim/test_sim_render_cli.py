"""`armlab render`: one frame (colour PNG, 16-bit depth PNG in mm) and the ground truth as JSON, from
an event/level or a scene file; bad input gets a clear error and exit code 2."""

import json
import subprocess
import sys

import cv2
import numpy as np


def run(*args):
    return subprocess.run([sys.executable, "-m", "armlab.cli", "render", *args], capture_output=True, text=True, timeout=300)


def test_render_event_writes_colour_depth_and_truth_and_a_scene_file_round_trips(tmp_path):
    result = run("--event", "pick_sort", "--level", "2", "--seed", "4", "--out", str(tmp_path / "c.png"),
                 "--depth", str(tmp_path / "d.png"), "--truth", str(tmp_path / "t.json"), "--no-noise")
    assert result.returncode == 0, result.stderr
    color = cv2.imread(str(tmp_path / "c.png"), cv2.IMREAD_UNCHANGED)
    depth = cv2.imread(str(tmp_path / "d.png"), cv2.IMREAD_UNCHANGED)
    assert color.shape == (720, 1280, 3) and color.dtype == np.uint8
    assert depth.shape == (720, 1280) and depth.dtype == np.uint16
    assert 900 < np.median(depth) < 1100  # the board, about 1 m below the camera, in mm
    truth = json.loads((tmp_path / "t.json").read_text())
    assert np.array(truth["camera"]["K"]).shape == (3, 3)
    assert (truth["camera"]["width"], truth["camera"]["height"]) == (1280, 720)
    T = np.array(truth["camera"]["T_world_camera"])
    assert T.shape == (4, 4) and T[2, 2] < -0.9  # OpenCV z axis looks down
    assert len(truth["objects"]) == 6
    obj = truth["objects"][0]
    assert obj["type"] == "block" and obj["size"] in ("large", "small") and len(obj["quat_wxyz"]) == 4
    # The truth file is a valid scene file: rendering it again gives the same objects.
    again = run("--scene", str(tmp_path / "t.json"), "--seed", "4", "--out", str(tmp_path / "c2.png"),
                "--truth", str(tmp_path / "t2.json"), "--no-noise")
    assert again.returncode == 0, again.stderr
    truth2 = json.loads((tmp_path / "t2.json").read_text())
    for a, b in zip(truth["objects"], truth2["objects"]):
        assert a["id"] == b["id"] and np.allclose(a["position_m"], b["position_m"], atol=0.001)


def test_render_refuses_bad_input_with_a_clear_error(tmp_path):
    result = run("--event", "juggle", "--out", str(tmp_path / "c.png"))
    assert result.returncode == 2 and "unknown event" in result.stderr
    bad_scene = tmp_path / "bad.json"
    bad_scene.write_text(json.dumps({"objects": [{"id": "a", "type": "block", "color": "red", "size": "large",
                                                  "position_m": [0.1, "nan", 0.0]}]}))
    result = run("--scene", str(bad_scene), "--out", str(tmp_path / "c.png"))
    assert result.returncode == 2 and "a" in result.stderr
    assert not (tmp_path / "c.png").exists()


def test_scene_command_prints_a_reproducible_scene_file(tmp_path):
    def scene(*args):
        return subprocess.run([sys.executable, "-m", "armlab.cli", "scene", *args], capture_output=True, text=True, timeout=120)

    first = scene("--event", "stack_high", "--level", "2", "--seed", "9")
    assert first.returncode == 0, first.stderr
    data = json.loads(first.stdout)
    assert len(data["objects"]) == 12
    assert scene("--event", "stack_high", "--level", "2", "--seed", "9").stdout == first.stdout
    tagged = json.loads(scene("--seed", "4", "--aruco").stdout)
    assert any("aruco_id" in obj for obj in tagged["objects"])
    assert scene("--event", "stack_high", "--level", "3").returncode == 2
