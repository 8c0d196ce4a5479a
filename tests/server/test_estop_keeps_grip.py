"""E-stop while carrying a block keeps it (issue 21, broken item 5): before, the e-stop's gripper halt set
the fingers' reference to where they were, so the squeeze that held the block went away and it fell ~40 mm.
Now the e-stop halts the arm and what is held stays held: fingers (RX200) and suction cup (UR3). Real HTTP
on the real-time simulation: grab a block, start carrying it away with a drop, e-stop mid-transfer; the
simulation's ground truth says the block is still in the gripper, at the height it was carried at."""

from __future__ import annotations

import httpx
import numpy as np
import pytest

import live
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.factory import make_sim_station
from armlab.workcell import load_workcell
from server.app import create_app

TOKEN = "estop-grip-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
# (block xy, drop xy) per workcell: in reach top-down, on the board, far enough apart for a long carry.
SPOTS = {"rx200_armlab": ((0.0, 0.25), (0.20, 0.15)), "ur3_suction": ((0.12, 0.30), (-0.20, 0.22))}
CARRIED_ABOVE_M = 0.05  # the block's centre this far above its resting height: it is being carried


@pytest.fixture(scope="module", params=sorted(SPOTS))
def station_url(request, tmp_path_factory):
    built = {}

    def factory():
        built["sim"] = make_sim_station(StationConfig(workcell=request.param), tmp_path_factory.mktemp("grip") / "db.sqlite3")
        return built["sim"]

    with live.serve(create_app(station_factory=factory, token=TOKEN)) as url:
        yield request.param, built["sim"].cell, url


def _block(cell) -> dict:
    return next(o for o in cell.truth()["objects"] if o["id"] == "b1")


def test_estop_while_carrying_keeps_the_block_in_the_gripper(station_url):
    workcell, cell, url = station_url
    edge_m = load_workcell(workcell).block_edge_m("large")
    (bx, by), (dx, dy) = SPOTS[workcell]
    cell.set_scene(Scene.from_dict({"objects": [{"id": "b1", "type": "block", "color": "red", "size": "large",
                                                 "position_m": [bx, by, edge_m / 2], "yaw_rad": 0.0}]}, workcell=workcell))
    with httpx.Client(base_url=url, timeout=120) as http:
        grabbed = http.post("/api/grab", params={"wait": "true"}, json={"position_m": [bx, by, edge_m]}, headers=AUTH)
        assert grabbed.status_code == 200 and grabbed.json()["job"]["state"] == "succeeded", grabbed.text
        assert cell.truth()["gripper"]["holding_id"] == "b1"
        started = http.post("/api/drop", json={"position_m": [dx, dy, 0.0]}, headers=AUTH)
        assert started.status_code == 202, started.text
        live.wait_for(lambda: _block(cell)["position_m"][2] > edge_m / 2 + CARRIED_ABOVE_M and cell.arm.is_moving(), 30, 0.005)
        assert http.post("/api/estop", headers=AUTH).status_code == 200
        live.wait_for(lambda: not cell.arm.is_moving(), 5, 0.005)
        halted_z = _block(cell)["position_m"][2]
        width_m = cell.gripper.read_state().width_m
        live.wait_sim(cell, 1.5)  # long enough for a released block to reach the board
        truth = cell.truth()
        block_z = _block(cell)["position_m"][2]
        assert truth["gripper"]["holding_id"] == "b1", f"{workcell}: the gripper let go of the block: {truth['gripper']}"
        assert block_z > edge_m / 2 + CARRIED_ABOVE_M - 0.005 and abs(block_z - halted_z) < 0.005, (
            f"{workcell}: the block fell from z = {halted_z * 1000:.1f} mm to {block_z * 1000:.1f} mm after the e-stop")
        assert abs(cell.gripper.read_state().width_m - width_m) < 0.001  # fingers (or cup) as they were
        job = http.get("/api/jobs/current").json()
        assert "cleanup failed" not in str(job), job
        http.post("/api/reset", headers=AUTH)
        assert np.isclose(_block(cell)["position_m"][2], block_z, atol=0.005)  # reset moves nothing, keeps the grip
