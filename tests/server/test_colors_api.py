"""Colour calibration over real HTTP (real-time simulation, real SQLite): a sample named by the operator
changes the colour perception reports at once, bad input is refused naming the field and changes
nothing, the samples survive a station restart, reset returns to the defaults; no frame is a 503."""

from __future__ import annotations

import httpx
from fastapi.testclient import TestClient

import live
from armlab.kinematics import load_arm
from armlab.station import Station, StationConfig
from armlab.store import Store
from armlab.vision import load_perception_config
from server.app import create_app

TOKEN = "colors-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
SCENE = {"objects": [
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.20, 0.019]},
    {"id": "blue", "type": "block", "color": "blue", "size": "large", "position_m": [-0.12, 0.22, 0.019]},
]}


def _block(client, color: str) -> dict | None:
    found = [b for b in client.get("/api/detections").json()["data"] if b["color"] == color and b["is_cube"]]
    return found[0] if found else None


def test_a_sample_changes_perception_at_once_persists_and_resets(tmp_path):
    db = tmp_path / "station.sqlite3"
    cell = live.start_cell(seed=5)
    try:
        with live.station_server(cell, db, TOKEN) as url, httpx.Client(base_url=url, timeout=30) as client:
            assert client.post("/api/sim/scene", headers=AUTH, json=SCENE).status_code == 200
            assert client.post("/api/calibrate?wait=true", headers=AUTH).json()["job"]["state"] == "succeeded"
            red = live.wait_for(lambda: _block(client, "red"), timeout_s=20)
            assert red["color_lab"] is not None and len(red["color_lab"]) == 3
            u, v = red["center_px"]
            before = client.get("/api/colors").json()
            assert before["samples"] == [] and "pink" in before["names"]

            # Bad input: 422 naming the field, nothing changes.
            for body, field in (({"u": u, "v": v, "color": "yelow"}, "color"), ({"u": 5000.0, "v": v, "color": "red"}, "u"),
                                ({"u": u, "v": 900.0, "color": "red"}, "v")):
                refused = client.post("/api/colors/samples", headers=AUTH, json=body)
                assert refused.status_code == 422, refused.text
                assert refused.json()["error"]["message"].startswith(f"{field}:"), refused.text
            bad_fit = client.post("/api/colors/fit", headers=AUTH, json={"samples": [{"u": u, "v": v, "color": "red"},
                                                                                   {"u": u, "v": v, "color": "purple"}]})
            assert bad_fit.status_code == 422 and "samples[1].color" in bad_fit.json()["error"]["message"]
            assert client.post("/api/colors/samples", json={"u": u, "v": v, "color": "pink"}).status_code == 401
            assert client.get("/api/colors").json()["samples"] == []
            assert _block(client, "red") is not None

            # Shift the model on purpose: this red cube is named pink; perception reads it pink at once.
            taught = client.post("/api/colors/samples", headers=AUTH, json={"u": u, "v": v, "color": "pink"})
            assert taught.status_code == 200, taught.text
            assert taught.json()["reading_before"]["name"] == "red" and taught.json()["samples"] == 1
            live.wait_for(lambda: _block(client, "pink"), timeout_s=20)
            assert _block(client, "blue") is not None  # the other cube keeps its colour

        # A restarted station on the same database uses the sample.
        with live.station_server(cell, db, TOKEN) as url, httpx.Client(base_url=url, timeout=30) as client:
            samples = client.get("/api/colors").json()["samples"]
            assert [s["name"] for s in samples] == ["pink"] and samples[0]["u"] == u
            assert client.post("/api/calibrate?wait=true", headers=AUTH).json()["job"]["state"] == "succeeded"
            live.wait_for(lambda: _block(client, "pink"), timeout_s=20)
            assert client.delete("/api/colors/samples", headers=AUTH).json() == {"samples": 0}
            live.wait_for(lambda: _block(client, "red"), timeout_s=20)

        assert Store(db).latest_color_calibration()["samples"] == []  # the reset was stored
    finally:
        cell.close()


def test_no_frame_yet_is_a_503_and_changes_nothing(tmp_path):
    """A station whose camera has delivered nothing (not started: no camera thread)."""
    cell = live.start_cell(seed=6)
    try:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), perception_config=load_perception_config(),
                          config=StationConfig(database_path=str(tmp_path / "db.sqlite3")), sim=cell, backend="sim")
        app = create_app(station_factory=lambda: station, token=TOKEN)
        with TestClient(app, base_url="http://127.0.0.1") as client:
            response = client.post("/api/colors/samples", headers=AUTH, json={"u": 10.0, "v": 10.0, "color": "red"})
            assert response.status_code == 503 and "no camera frame" in response.json()["error"]["message"], response.text
            assert client.get("/api/colors").json()["samples"] == []
    finally:
        cell.close()
