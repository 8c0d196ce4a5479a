"""Issue 21 History: the event log is kept in the station's database, so a new server on the same database (a restart)
still finds what the old one logged, and so does a page loaded afresh (it only asks GET /api/history/events)."""

from __future__ import annotations

import httpx
import pytest

import live

TOKEN = "history-restart-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


@pytest.fixture(scope="module")
def cell():
    started = live.start_cell(seed=31)
    yield started
    started.close()


def test_events_survive_a_server_restart(cell, tmp_path):
    db = tmp_path / "station.sqlite3"
    with live.station_server(cell, db, TOKEN) as url, httpx.Client(base_url=url, timeout=60) as http:
        assert http.put("/api/speed", json={"speed_percent": 35}, headers=AUTH).status_code == 200
        assert http.post("/api/estop", headers=AUTH).status_code == 200
        assert http.post("/api/reset", headers=AUTH).status_code == 200
    with live.station_server(cell, db, TOKEN) as url, httpx.Client(base_url=url, timeout=60) as http:
        assert http.get("/api/speed").json()["speed_percent"] == 100.0  # a new station starts at full speed
        kept = http.get("/api/history/events", params={"limit": 5000}).json()["data"]
        messages = [e["message"] for e in kept]
        assert "speed override set to 35 %" in messages
        assert any(e["level"] == "error" and e["message"].startswith("E-stop") for e in kept)
        assert messages.count("station started (sim)") == 2, messages  # both lives of the station, newest first
        assert kept[0]["time_s"] >= kept[-1]["time_s"]
