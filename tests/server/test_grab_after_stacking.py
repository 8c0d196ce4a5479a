"""Clicking the block just stacked (issue 21, broken item 2): after a drop the arm stays over the spot, and
pixel-to-world answered with the depth remembered from before the drop (the lower block's top), so a grab
clicked there went for the lower block. The remembered depth of a spot is never older than the last motion
through it: hidden and changed since, the spot is not guessed (pixel-to-world and the grab refuse saying how
to see it); once the arm is out of the way the click grabs the top block. Real HTTP on the real-time RX200
simulation, calibrated from the board tags; ground truth from the simulation."""

from __future__ import annotations

import httpx
import numpy as np
import pytest

import live
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.factory import make_sim_station
from armlab.vision.pixel_world import world_to_pixel
from armlab.workcell import load_workcell
from server.app import create_app

TOKEN = "after-stack-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
EDGE_M = load_workcell("rx200_armlab").block_edge_m("large")
SMALL_M = load_workcell("rx200_armlab").block_edge_m("small")  # the issue: a small block stacked on a large one (top 63 mm)
BASE_XY, LOOSE_XY = (0.10, 0.22), (-0.10, 0.22)


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    built = {}

    def factory():
        built["sim"] = make_sim_station(StationConfig(sim={"time_scale": live.FAST_TIME_SCALE}), tmp_path_factory.mktemp("stack") / "db.sqlite3")
        return built["sim"]

    with live.serve(create_app(station_factory=factory, token=TOKEN)) as url:
        yield built["sim"], url


def _truth(cell) -> dict:
    return {o["id"]: np.asarray(o["position_m"], float) for o in cell.truth()["objects"]}


def _holding_the_loose_block(cell, http) -> None:
    """The red base and the loose blue block on the board, the camera calibrated, the blue block grabbed."""
    cell.set_scene(Scene.from_dict({"objects": [
        {"id": "base", "type": "block", "color": "red", "size": "large", "position_m": [*BASE_XY, EDGE_M / 2], "yaw_rad": 0.0},
        {"id": "loose", "type": "block", "color": "blue", "size": "small", "position_m": [*LOOSE_XY, SMALL_M / 2], "yaw_rad": 0.0},
    ]}))
    homed = http.post("/api/arm/home", params={"wait": "true"}, headers=AUTH)
    assert homed.status_code == 200, homed.text
    calibrated = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH)
    assert calibrated.json()["job"]["state"] == "succeeded", calibrated.text
    live.wait_for(lambda: len(http.get("/api/detections").json()["data"]) == 2, 20, 0.1)
    grabbed = http.post("/api/grab", params={"wait": "true"}, json={"position_m": [*LOOSE_XY, SMALL_M]}, headers=AUTH)
    assert grabbed.json()["job"]["state"] == "succeeded", grabbed.text


def test_a_click_on_the_block_just_stacked_never_goes_for_the_one_below(served):
    sim, url = served
    cell = sim.cell
    with httpx.Client(base_url=url, timeout=120) as http:
        _holding_the_loose_block(cell, http)
        dropped = http.post("/api/drop", params={"wait": "true"}, json={"position_m": [*BASE_XY, EDGE_M]}, headers=AUTH)
        assert dropped.json()["job"]["state"] == "succeeded", dropped.text
        stacked = _truth(cell)
        assert np.linalg.norm(stacked["loose"][:2] - BASE_XY) < 0.01 and abs(stacked["loose"][2] - EDGE_M - SMALL_M / 2) < 0.005
        q_after_drop = np.asarray(http.get("/api/status").json()["joints_rad"])

        top_m = np.array([*stacked["loose"][:2], EDGE_M + SMALL_M])
        u, v = (float(c) for c in world_to_pixel(sim.station.calibration, top_m[None, :])[0])
        live.wait_sim(cell, 0.5)  # frames taken with the arm still over the stack
        readout = http.post("/api/pixel-to-world", json={"u": u, "v": v})
        if readout.status_code == 200:  # seen (or remembered since the drop): the new top, never the block below
            assert abs(readout.json()["position_m"][2] - top_m[2]) < 0.008, readout.json()
        else:
            assert readout.status_code == 409 and "move the arm" in readout.json()["error"]["message"], readout.text
        grab = http.post("/api/grab", params={"wait": "true"}, json={"u": u, "v": v}, headers=AUTH)
        if grab.status_code == 409:  # refused with the way out, nothing moved: move the arm away and click again
            assert "move the arm" in grab.json()["error"]["message"], grab.text
            assert np.allclose(http.get("/api/status").json()["joints_rad"], q_after_drop, atol=2e-3)
            assert http.post("/api/arm/sleep", params={"wait": "true"}, headers=AUTH).status_code == 200
            live.wait_sim(cell, 0.5)
            grab = http.post("/api/grab", params={"wait": "true"}, json={"u": u, "v": v}, headers=AUTH)
        assert grab.status_code == 200, grab.text
        job = grab.json()["job"]
        truth = cell.truth()
        assert job["state"] == "succeeded" and truth["gripper"]["holding_id"] == "loose", (job, truth["gripper"])
        assert np.linalg.norm(_truth(cell)["base"] - stacked["base"]) < 0.003  # the block below stayed put


def test_a_block_let_go_over_a_hidden_spot_is_not_read_from_the_old_depth(served):
    """The arm hovers over the red block (hiding it from the camera), lets the blue one go onto it: the spot's
    remembered depth is the red top from before. Pixel-to-world and a grab there refuse saying how to see it
    (nothing moves); after Sleep the same click grabs the blue block, the red one stays."""
    sim, url = served
    cell = sim.cell
    with httpx.Client(base_url=url, timeout=120) as http:
        _holding_the_loose_block(cell, http)
        hover = http.post("/api/arm/pose", params={"wait": "true"}, headers=AUTH,
                          json={"position_m": [*BASE_XY, EDGE_M + 0.045], "pitch_rad": 1.5708, "yaw_rad": 0.0})
        assert hover.status_code == 200, hover.text
        live.wait_sim(cell, 0.5)
        assert http.post("/api/gripper", params={"wait": "true"}, json={"action": "release"}, headers=AUTH).status_code == 200
        live.wait_sim(cell, 1.0)
        stacked = _truth(cell)
        assert np.linalg.norm(stacked["loose"][:2] - BASE_XY) < 0.012 and abs(stacked["loose"][2] - EDGE_M - SMALL_M / 2) < 0.006, stacked
        top_m = np.array([*stacked["loose"][:2], EDGE_M + SMALL_M])
        u, v = (float(c) for c in world_to_pixel(sim.station.calibration, top_m[None, :])[0])
        q_hover = np.asarray(http.get("/api/status").json()["joints_rad"])
        readout = http.post("/api/pixel-to-world", json={"u": u, "v": v})
        if readout.status_code == 200:
            assert abs(readout.json()["position_m"][2] - top_m[2]) < 0.008, readout.json()  # never the red top below
        else:
            assert readout.status_code == 409 and "move the arm" in readout.json()["error"]["message"], readout.text
        grab = http.post("/api/grab", params={"wait": "true"}, json={"u": u, "v": v}, headers=AUTH)
        if grab.status_code == 409:
            assert "move the arm" in grab.json()["error"]["message"], grab.text
            assert np.allclose(http.get("/api/status").json()["joints_rad"], q_hover, atol=2e-3)  # nothing moved
            assert http.post("/api/arm/sleep", params={"wait": "true"}, headers=AUTH).status_code == 200
            live.wait_sim(cell, 0.5)
            grab = http.post("/api/grab", params={"wait": "true"}, json={"u": u, "v": v}, headers=AUTH)
        assert grab.status_code == 200, grab.text
        assert grab.json()["job"]["state"] == "succeeded" and cell.truth()["gripper"]["holding_id"] == "loose", grab.json()["job"]
        assert np.linalg.norm(_truth(cell)["base"] - stacked["base"]) < 0.003
