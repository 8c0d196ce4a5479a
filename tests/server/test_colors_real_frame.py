"""Colour calibration on a real frame, end to end (issue 17 item 2): a station with no arm on the recorded
camera plays ../shared/data/rob550_dev's image_204shuffled; the shipped colours read its pink cube (labelled
at (852, 522)) as red; one operator sample over real HTTP makes perception report it pink at once, while
the red cube (labelled at (1008, 284)) stays red."""

from __future__ import annotations

import math
from pathlib import Path

import httpx
import pytest

from armlab.station import StationConfig
from live import serve, wait_for

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "rob550_dev"
TOKEN = "real-colours-token"
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "operator"}
PINK, RED = (852, 522), (1008, 284)

pytestmark = pytest.mark.skipif(not (DATA / "image_204shuffled.png").exists(),
                                reason=f"the real development frames are not at {DATA} (see its README: not copied into the repo)")


def _colour_at(client, pixel) -> str | None:
    near = [b for b in client.get("/api/detections").json()["data"] if math.dist(b["center_px"], pixel) < 15]
    return near[0]["color"] if near else None


def test_one_sample_on_a_real_frame_names_the_pink_cube(tmp_path):
    from armlab.station.factory import make_device_station
    from server.app import create_app

    db = tmp_path / "station.sqlite3"
    made = make_device_station(StationConfig(database_path=str(db)), "none", "none",
                               {"type": "recorded", "source": str(DATA), "frame": "204shuffled", "fps": 10}, db_path=db, board="auto")
    app = create_app(station_factory=lambda: made, token=TOKEN)
    with serve(app) as url, httpx.Client(base_url=url, timeout=60) as client:
        job = client.post("/api/calibrate?wait=true", headers=AUTH).json()["job"]
        assert job["state"] == "succeeded", job
        assert wait_for(lambda: _colour_at(client, PINK), timeout_s=30) == "red"  # the shipped defaults' misread
        assert _colour_at(client, RED) == "red"
        taught = client.post("/api/colors/samples", headers=AUTH, json={"u": float(PINK[0]), "v": float(PINK[1]), "color": "pink"})
        assert taught.status_code == 200, taught.text
        wait_for(lambda: _colour_at(client, PINK) == "pink", timeout_s=30)
        assert _colour_at(client, RED) == "red"
