"""POST /api/calibrate/points: clicked pixels and their world points are bounded like every other pixel and
coordinate of the API (server/wire_base.py Pixel, Coordinate): an absurd value is a 422 naming the field,
no calibration job starts and the calibration in use is unchanged. Before, a world point of 1e300 m
started a job that failed with a 300-digit number in its message, a pixel of 1e9 started a job too, and
one (x, y, z) point among (x, y) ones failed the job with numpy's "inhomogeneous shape" ValueError.
Real HTTP, real-time simulation."""

from __future__ import annotations

import httpx
import pytest

import live

TOKEN = "clicked-points-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
GOOD = [([300.0, 200.0], [0.0, 0.1]), ([900.0, 200.0], [0.2, 0.1]), ([300.0, 500.0], [0.0, 0.3]), ([900.0, 500.0], [0.2, 0.3])]

cell, url = live.module_fixtures(seed=3, token=TOKEN)


@pytest.mark.parametrize(("index", "key", "value", "field"), [
    (0, "world_m", [1e300, 0.0], "points.0.world_m.0"),
    (2, "world_m", [0.0, 0.1, -1e6], "points.2.world_m.2"),
    (1, "pixel", [1e9, 200.0], "points.1.pixel.0"),
    (3, "pixel", [300.0, -5.0], "points.3.pixel.1"),
    (1, "world_m", [0.2, 0.1, 0.0], "world_m must be (x, y) for every point or (x, y, z) for every point"),
])
def test_an_absurd_clicked_point_is_refused_before_any_job(url, index, key, value, field):
    points = [{"pixel": list(pixel), "world_m": list(world)} for pixel, world in GOOD]
    points[index][key] = value
    with httpx.Client(base_url=url, timeout=30.0) as http:
        before = http.get("/api/calibration").json()
        job_before = http.get("/api/jobs/current").json()["job"]
        response = http.post("/api/calibrate/points", json={"points": points}, headers=AUTH)
        assert response.status_code == 422, response.text
        message = response.json()["error"]["message"]
        assert field in message and len(message) < 300, message
        assert http.get("/api/jobs/current").json()["job"] == job_before  # no job started
        assert http.get("/api/calibration").json() == before
