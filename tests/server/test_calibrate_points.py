"""POST /api/calibrate/points: calibration from >= 4 clicked pixels with known world points, over a
real server on the real-time simulation, against ground truth; bad points fail clearly and the old
calibration stays."""

from __future__ import annotations

import httpx
import numpy as np

import live
from armlab.vision.geometry import project_points

TOKEN = "points-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
NINE = [(x, y) for y in (-0.125, 0.15, 0.425) for x in (-0.4, 0.0, 0.4)]

cell, url = live.module_fixtures(seed=6, token=TOKEN)


def _clicks(cell, points_xy):
    truth = cell.truth()["camera"]
    world = np.array([[x, y, 0.0] for x, y in points_xy])
    pixels = np.round(project_points(np.asarray(truth["T_world_camera"]), np.asarray(truth["K"]), np.asarray(truth["dist"]), world))
    return [{"pixel": [float(u), float(v)], "world_m": [x, y]} for (u, v), (x, y) in zip(pixels, points_xy)]


def test_clicked_points_calibrate_the_station_and_bad_points_keep_it(cell, url):
    true_position = np.asarray(cell.truth()["camera"]["T_world_camera"])[:3, 3]
    with httpx.Client(base_url=url, timeout=60.0) as http:
        response = http.post("/api/calibrate/points", params={"wait": "true"}, json={"points": _clicks(cell, NINE)}, headers=AUTH)
        assert response.status_code in (200, 202), response.text
        job = response.json()["job"]
        assert job["state"] == "succeeded", job
        assert job["result"]["reprojection_error_px"] < 0.6 and len(job["result"]["point_errors_px"]) == 9
        info = http.get("/api/calibration").json()
        assert info["calibrated"] and info["method"] == "points"
        assert np.linalg.norm(np.asarray(info["camera_position_m"]) - true_position) < 0.005
        collinear = [{"pixel": [100.0 + 50 * i, 200.0 + 10 * i], "world_m": [-0.3 + 0.2 * i, 0.1]} for i in range(4)]
        for bad, message in ((_clicks(cell, NINE[:3]), "at least 4 points"), (collinear, "collinear")):
            job = http.post("/api/calibrate/points", params={"wait": "true"}, json={"points": bad}, headers=AUTH).json()["job"]
            assert job["state"] == "failed" and message in job["message"], job
            assert http.get("/api/calibration").json()["camera_position_m"] == info["camera_position_m"]  # the old one kept
        assert http.post("/api/calibrate/points", json={"points": [{"pixel": [1.0], "world_m": [0.0, 0.0]}]}, headers=AUTH).status_code == 422
