"""Calibration looks at a frame taken after it was asked for. The newest frame may show the world as it
was up to a frame period ago (seconds on a loaded machine); calibrating from it right after the scene
changed (the checkerboard put away) solved from the old scene: on a busy CI machine it found tags 2 and 3
only, the intrinsics checkerboard still lying over tags 1 and 4 in a frame from before it was removed."""

from __future__ import annotations

import time

import numpy as np

from armlab import skills
from station_helpers import live

CAMERA_FPS = 2.0  # one frame in 0.5 s: the newest frame is nearly always older than a request


def _cover_tags_1_and_4(cell) -> None:
    """The intrinsics checkerboard (12 x 9 squares of 30 mm with its margin) lying on the board at x = -0.25,
    its long side along y: tags 1 (y = -0.025) and 4 (y = 0.275) are under it."""
    R_world_board = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    cell.place_checkerboard([-0.25, 0.125, 0.005], R_world_board)


def test_calibrate_right_after_the_scene_changed_uses_the_new_scene(tmp_path):
    cell = live.start_cell(seed=0, camera_fps=CAMERA_FPS)
    station = live.make_station(cell, tmp_path / "station.sqlite3")
    try:
        _cover_tags_1_and_4(cell)
        station.frame_after(time.time())  # the camera has shown the covered tags
        covered = skills.calibrate(station)
        assert covered.wait(30)
        assert covered.state == "failed" and "missing [1, 4]" in covered.message, covered.to_dict()

        cell.place_checkerboard()  # put away: every tag in view from the next frame on
        uncovered = skills.calibrate(station)
        assert uncovered.wait(30)
        assert uncovered.state == "succeeded", uncovered.to_dict()
    finally:
        station.close()
        cell.close()
