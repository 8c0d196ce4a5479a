"""The station warns in /api/status when the calibrated camera has moved: the perception thread's
camera-moved check (armlab.vision.drift) on the real-time simulation, mount bumped by 1 degree."""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).parents[1] / "server"))
import live  # noqa: E402
from armlab import skills  # noqa: E402


def test_status_says_camera_moved_after_a_bump_and_not_before(tmp_path):
    cell = live.start_cell(seed=4)
    station = live.make_station(cell, tmp_path / "station.sqlite3")
    try:
        job = skills.calibrate(station)
        assert job.wait(30) and job.state == "succeeded", job.message
        assert station.status()["calibrated"] and station.status()["camera_warning"] is None
        live.wait_sim(cell, 7.0, timeout_s=60)  # two check periods of the unmoved camera
        assert station.status()["camera_warning"] is None
        bump = np.eye(4)
        bump[:3, :3] = cv2.Rodrigues(np.array([np.radians(1.0), 0.0, 0.0]))[0]
        cell.bump_camera(bump)
        warning = live.wait_for(lambda: station.status()["camera_warning"], timeout_s=60)
        assert warning.startswith("camera moved: recalibrate")
        job = skills.calibrate(station)
        assert job.wait(30) and job.state == "succeeded", job.message
        live.wait_for(lambda: station.status()["camera_warning"] is None, timeout_s=10)  # the next perception pass
        live.wait_sim(cell, 7.0, timeout_s=60)  # and it stays quiet: the new calibration fits
        assert station.status()["camera_warning"] is None
    finally:
        station.close()
        cell.close()


# A restored calibration checked before it is trusted, and self-recalibration: test_calibration_trust.py.
