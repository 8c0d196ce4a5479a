"""The simulation-only routes of this stop (POST/DELETE /api/sim/checkerboard) on a station that is not the
simulation's (a station on device drivers: here the simulated devices without the simulation handle, as
make_device_station builds one): 404 'not_found' saying the route exists only with the simulation, and nothing in
the cell moves (the checkerboard stays parked: MuJoCo's mocap pose
is the truth); without the token it is 401 first. The intrinsics routes, which are not simulation-only, still answer. Real HTTP."""

from __future__ import annotations

import httpx
import numpy as np

import live
from armlab.kinematics import load_arm
from armlab.station import Station, StationConfig

TOKEN = "not-sim-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


class DeviceStationOnCell:
    """create_app's station factory: a Station on the cell's devices with no simulation handle (sim=None)."""

    def __init__(self, cell, db_path) -> None:
        self.station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), backend="device",
                               config=StationConfig(database_path=str(db_path)))
        self.station.start()

    def close(self) -> None:
        self.station.close()


def checkerboard_mocap(cell) -> np.ndarray:
    model, data = cell.model, cell._data
    return np.array(data.mocap_pos[model.body_mocapid[model.body("checkerboard").id]])


def test_checkerboard_routes_are_404_without_the_simulation(tmp_path):
    from server.app import create_app

    cell = live.start_cell(seed=1)
    try:
        parked = checkerboard_mocap(cell)
        app = create_app(station_factory=lambda: DeviceStationOnCell(cell, tmp_path / "s.sqlite3"), token=TOKEN)
        with live.serve(app) as url, httpx.Client(base_url=url, timeout=30.0) as http:
            for method, body in (("POST", {"position_m": [0.0, 0.0, 0.5]}), ("DELETE", None)):
                response = http.request(method, "/api/sim/checkerboard", json=body, headers=AUTH)
                assert response.status_code == 404, response.text
                error = response.json()["error"]
                assert error["code"] == "not_found" and "only when the backend is the simulation" in error["message"]
                assert http.request(method, "/api/sim/checkerboard", json=body).status_code == 401  # no token: refused first
            assert http.get("/api/intrinsics").json()["source"] == "factory"
            assert http.post("/api/intrinsics/session", headers=AUTH).status_code == 200
            assert http.delete("/api/intrinsics/session", headers=AUTH).status_code == 200
        assert np.array_equal(checkerboard_mocap(cell), parked)
    finally:
        cell.close()
