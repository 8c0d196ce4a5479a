"""The real-frame scorer (armlab/vision/real_eval.py) on hand-made labels: matching by pixel distance,
stack levels from the labels, hidden stack members neither required nor extras, distractors counted."""

from __future__ import annotations

import json

import numpy as np
import pytest

from armlab.vision.real_eval import Detection, load_labels, match_by_distance, score_frame
from armlab.vision.rgbd_files import read_color, read_depth


def _labels(tmp_path, cubes, **extra):
    path = tmp_path / "image_x.labels.json"
    path.write_text(json.dumps({"image": "image_x.png", "cubes": cubes, **extra}))
    return load_labels(path)


def _det(u, v, color="red", size="large", level=1, height_mm=38.0):
    return Detection(u, v, color, size, level, height_mm, (0.0, 0.0))


def test_matching_takes_the_closest_pairs_once_and_respects_the_radius():
    a = np.array([[0, 0], [10, 0], [100, 100]])
    b = np.array([[9, 0], [1, 0], [300, 300]])
    assert sorted(match_by_distance(a, b, 5)) == [(0, 1), (1, 0)]
    assert match_by_distance(a, np.zeros((0, 2)), 5) == []


def test_a_frame_is_scored_with_colour_size_level_and_extras(tmp_path):
    labels = _labels(tmp_path, [
        {"color": "purple", "size": "large", "u": 100, "v": 100, "depth_height_mm": 35},
        {"color": "red", "size": "small", "u": 300, "v": 100},
        {"color": "blue", "size": "large", "u": 500, "v": 100, "stacked_on_another": True},
        {"color": "green", "size": "large", "u": 510, "v": 105, "stacked_on_another": False, "occluded": True, "uncertain": True},
        {"color": "yellow", "size": "small", "u": 700, "v": 100, "uncertain": True},
    ], other_cubes=[{"color": "black", "size": "large", "u": 900, "v": 100}], occluders=[{"u": 1100, "v": 600}])
    assert [c.color for c in labels.cubes][0] == "violet"  # the labels' purple is the project's violet
    assert [c.stack_level for c in labels.cubes][:3] == [1, 1, 2]
    s = score_frame(labels, [
        _det(102, 100, "violet", "large", height_mm=33.0),  # right
        _det(300, 103, "orange", "small"),  # wrong colour
        _det(501, 100, "blue", "large", level=1),  # wrong stack level
        _det(511, 106, "green", "large"),  # a hidden member reported: not an extra
        _det(900, 101, "unknown", "large"),  # the black cube
        _det(1100, 600),  # on the hand
        _det(50, 600),  # nothing there
    ], radius_px=20, mm_per_px=1.1)
    assert (s.labelled, s.found, s.color_right, s.size_right, s.level_right) == (3, 3, 2, 3, 2)
    assert (s.uncertain_labelled, s.uncertain_found, s.other_labelled, s.other_found, s.hidden_members) == (1, 0, 1, 1, 1)
    assert (s.extras, s.distractors_called_cubes) == (1, 1)
    assert s.height_errors_mm == [-2.0]
    assert sorted(s.centre_errors_mm) == pytest.approx([1.1, 2.2, 3.3])


def test_malformed_labels_name_the_file_and_entry(tmp_path):
    path = tmp_path / "image_bad.labels.json"
    path.write_text(json.dumps({"cubes": [{"color": "red", "u": 1}]}))
    with pytest.raises(ValueError, match=r"image_bad.labels.json.*cubes\[0\]"):
        load_labels(path)


def test_a_depth_png_of_the_wrong_bit_depth_or_size_is_refused_naming_the_file(tmp_path):
    import cv2

    cv2.imwrite(str(tmp_path / "depth_8bit.png"), np.zeros((720, 1280), np.uint8))
    cv2.imwrite(str(tmp_path / "depth_small.png"), np.zeros((480, 640), np.uint16))
    cv2.imwrite(str(tmp_path / "image_grey.png"), np.zeros((720, 1280), np.uint8))
    with pytest.raises(ValueError, match=r"depth_8bit.png must be single-channel 16-bit.*8-bit"):
        read_depth(tmp_path / "depth_8bit.png", (1280, 720))
    with pytest.raises(ValueError, match=r"depth_small.png is 640x480 but its colour frame is 1280x720"):
        read_depth(tmp_path / "depth_small.png", (1280, 720))
    with pytest.raises(ValueError, match=r"image_grey.png must be 8-bit BGR"):
        read_color(tmp_path / "image_grey.png")
    with pytest.raises(ValueError, match=r"cannot read depth image .*missing.png"):
        read_depth(tmp_path / "missing.png")
