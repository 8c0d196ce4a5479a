"""POST /api/calibrate/arm-camera: the camera calibrated from the arm through a real server on the real-time
simulation (frames taken after each move, not before), against ground truth; it cross-checks the tag
calibration in use and leaves it in use; only the controller may start it."""

from __future__ import annotations

import httpx
import numpy as np

import live

TOKEN = "arm-camera-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}

cell, url = live.module_fixtures(seed=4, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


def test_the_route_calibrates_from_the_arm_and_keeps_the_tag_calibration(cell, url):
    with httpx.Client(base_url=url, timeout=180.0) as http:
        assert http.post("/api/calibrate/arm-camera").status_code in (401, 403)
        tags = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert tags["state"] == "succeeded", tags
        before = http.get("/api/calibration").json()
        job = http.post("/api/calibrate/arm-camera", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert job["state"] == "succeeded", job
        result = job["result"]
        assert len(result["poses_used"]) >= 12 and len(result["residuals_mm"]) == len(result["poses_used"])
        position_m, angle_deg = cell.camera_pose_error(np.array(result["T_world_camera"]))
        assert position_m < 0.003 and angle_deg < 0.5
        assert result["tag_calibration"]["method"] == "tags" and result["tag_calibration"]["position_mm"] < 5.0
        assert "from the tags calibration" in job["message"]
        after = http.get("/api/calibration").json()
        assert after["method"] is None and after["T_world_camera"] == before["T_world_camera"]
