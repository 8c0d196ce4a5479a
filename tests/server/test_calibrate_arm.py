"""POST /api/calibrate/arm through a real server on the real-time simulation of the real arm (realism real):
only the controller may start it; refused before the camera is calibrated; after it, the arm calibration's job
succeeds with the residual before and after, and GET /api/status carries arm_calibration {calibrated,
residual_mm, at}."""

from __future__ import annotations

import httpx
import pytest

import live

TOKEN = "arm-calibration-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def url(tmp_path_factory):
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=True, seed=3, realism="real", time_scale=live.FAST_TIME_SCALE))
    cell.start()
    try:
        with live.station_server(cell, tmp_path_factory.mktemp("station") / "station.sqlite3", TOKEN) as base_url:
            yield base_url
    finally:
        cell.close()


def test_the_route_calibrates_the_arm_and_the_status_shows_it(url):
    with httpx.Client(base_url=url, timeout=600.0) as http:
        assert http.post("/api/calibrate/arm").status_code in (401, 403)
        assert http.get("/api/status").json()["arm_calibration"] == {"calibrated": False, "residual_mm": None, "at": None}
        refused = http.post("/api/calibrate/arm", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert refused["state"] == "failed" and "camera is not calibrated" in refused["message"]
        tags = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert tags["state"] == "succeeded", tags["message"]
        job = http.post("/api/calibrate/arm", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert job["state"] == "succeeded", job["message"]
        result = job["result"]
        assert len(result["poses_used"]) >= 12 and result["residual_before_mm"] > 15.0 and result["residual_mm"] < 2.5
        status = http.get("/api/status").json()["arm_calibration"]
        assert status["calibrated"] and abs(status["residual_mm"] - result["residual_mm"]) < 1e-3 and status["at"] > 0
