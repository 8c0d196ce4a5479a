"""The app factory: lifespan starts and stops the station; health works in-process (TestClient)."""

from fastapi.testclient import TestClient

import live
from server.app import create_app


def test_health_reports_ok_and_version_and_lifespan_closes_the_station(tmp_path):
    cell = live.start_cell()
    made = []

    def factory():
        made.append(live.StationOnCell(cell, tmp_path / "db.sqlite3"))
        return made[-1]

    try:
        app = create_app(station_factory=factory, token="t")
        with TestClient(app, base_url="http://127.0.0.1") as client:  # a Host the station serves
            response = client.get("/api/health")
            assert response.status_code == 200 and response.json()["status"] == "ok"
            assert client.get("/api/status").json()["state"] == "idle"
            assert app.state.station is made[0].station
        assert app.state.station is None  # shut down by the lifespan
        assert not made[0].station.is_running  # its threads were stopped
    finally:
        cell.close()


def test_generated_token_when_none_is_given(monkeypatch):
    monkeypatch.delenv("ARMLAB_TOKEN", raising=False)
    first, second = create_app(station_factory=lambda: None), create_app(station_factory=lambda: None)
    assert len(first.state.token) >= 20 and first.state.token != second.state.token
    monkeypatch.setenv("ARMLAB_TOKEN", "from-env")
    assert create_app(station_factory=lambda: None).state.token == "from-env"
    assert create_app(station_factory=lambda: None, token="explicit").state.token == "explicit"
