"""POST /api/intrinsics/accept?recalibrate=true when the recalibration cannot succeed (the board tags are
covered): the measured intrinsics are in use, the recalibration job fails saying why, and the old camera
calibration stays in use exactly as it was (pose and K), reported outdated. Real HTTP, real-time simulation,
real SQLite. Truth: the calibration read over the API before the accept."""

from __future__ import annotations

import httpx

import live
from armlab.devices.sim.checkerboard import calibration_poses
from armlab.vision import load_perception_config

TOKEN = "accept-recalibrate-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


def covered_board_scene() -> dict:
    """A large block on every board tag (nothing else): the tag calibration finds no tag."""
    tags = load_perception_config().tags.board_tags
    return {"objects": [{"id": f"cover{tag_id}", "type": "block", "color": "red", "size": "large", "position_m": [x, y, 0.019]}
                        for tag_id, (x, y) in sorted(tags.items())]}


def test_accept_with_a_failing_recalibration_keeps_the_old_calibration(tmp_path):
    cell = live.start_cell(seed=7)
    try:
        with live.station_server(cell, tmp_path / "station.sqlite3", TOKEN) as url, httpx.Client(base_url=url, timeout=30) as client:
            calibrated = client.post("/api/calibrate?wait=true", headers=AUTH).json()["job"]
            assert calibrated["state"] == "succeeded", calibrated
            before = client.get("/api/calibration").json()

            assert client.post("/api/intrinsics/session", headers=AUTH).status_code == 200
            for position_m, rotation_rad in calibration_poses(11, seed=3):
                placed = client.post("/api/sim/checkerboard", headers=AUTH,
                                     json={"position_m": list(position_m), "rotation_rad": list(rotation_rad)})
                assert placed.status_code == 200, placed.text
                assert client.post("/api/intrinsics/capture", headers=AUTH).status_code == 200
            solved = client.post("/api/intrinsics/solve", headers=AUTH)
            assert solved.status_code == 200, solved.text
            fx = solved.json()["solution"]["fx"]
            assert abs(fx - before["K"][0][0]) > 1e-6  # the solve differs from the calibration's K

            client.delete("/api/sim/checkerboard", headers=AUTH)
            assert client.post("/api/sim/scene", headers=AUTH, json=covered_board_scene()).status_code == 200
            live.wait_sim(cell, 0.3)  # frames with the tags covered

            accepted = client.post("/api/intrinsics/accept?recalibrate=true", headers=AUTH)
            assert accepted.status_code == 200, accepted.text
            job_id = accepted.json()["job"]["id"]
            job = live.wait_for(lambda: (lambda j: j if j["id"] == job_id and j["state"] != "running" else None)(
                client.get("/api/jobs/current").json()["job"]), timeout_s=30)
            assert job["state"] == "failed" and "tag" in job["message"], job

            after = client.get("/api/calibration").json()
            assert after["calibrated"] is True
            assert after["T_world_camera"] == before["T_world_camera"] and after["K"] == before["K"]
            info = client.get("/api/intrinsics").json()
            assert info["source"] == "measured" and info["intrinsics"]["fx"] == fx
            assert info["calibration_outdated"] is True
            assert client.get("/api/status").json()["state"] == "idle"
    finally:
        cell.close()
