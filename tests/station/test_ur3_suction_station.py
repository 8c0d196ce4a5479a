"""The station on the UR3 suction workcell (issue 12): it calibrates from the UR3 board's own tags, a
click-grab lifts a block with the suction cup and a click-drop puts it where the pixel points (ground
truth within 10 mm); a cup landing on the block's edge does not seal, and the grab job fails saying so
with the block left where it was. Fast-mode simulation, synchronous station."""

from __future__ import annotations

import math

import numpy as np

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import Scene
from armlab.station import State
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.vision.pixel_world import world_to_pixel
from armlab.workcell import load_workcell, load_workcell_arm

WORKCELL = "ur3_suction"
EDGE_M = load_workcell(WORKCELL).block_edge_m("large")
BLOCK = {"id": "b1", "type": "block", "color": "yellow", "size": "large", "position_m": [0.12, 0.30, EDGE_M / 2],
         "yaw_rad": 0.3, "aruco_id": 100}
DROP_SPOT_M = (-0.20, 0.22)


def _station(tmp_path, **config):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=4, workcell=WORKCELL), scene=Scene.from_dict({"objects": [BLOCK]}))
    cell.start()
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(WORKCELL),
                      config=StationConfig(workcell=WORKCELL, **config), store=Store(tmp_path / "s.sqlite3"), sim=cell,
                      synchronous=True)
    station.start()
    job = skills.calibrate(station)
    assert job.wait(60) and job.state == "succeeded", job.message
    station.fresh_perception()
    return station, cell


def truth(station, object_id: str = "b1") -> np.ndarray:
    return np.asarray(next(o for o in station.sim.truth()["objects"] if o["id"] == object_id)["position_m"], float)


def test_click_grab_and_click_drop_with_the_suction_cup(tmp_path):
    station, cell = _station(tmp_path)
    try:
        top = truth(station) + [0.0, 0.0, EDGE_M / 2]
        job = skills.grab(station, pixel=tuple(world_to_pixel(station.calibration, top[None, :])[0]))
        assert job.wait(120) and job.state == "succeeded", job.message
        assert cell.truth()["gripper"]["holding_id"] == "b1" and truth(station)[2] > EDGE_M  # lifted by the vacuum
        spot = np.array([*DROP_SPOT_M, 0.0])
        job = skills.drop(station, pixel=tuple(world_to_pixel(station.calibration, spot[None, :])[0]))
        assert job.wait(120) and job.state == "succeeded", job.message
        landed = truth(station)
        assert math.dist(landed[:2], spot[:2]) < 0.010, f"landed {landed} for the spot {spot}"
        assert abs(landed[2] - EDGE_M / 2) < 0.004 and cell.truth()["gripper"]["holding_id"] is None
    finally:
        station.close()
        cell.close()


def test_a_cup_landing_on_the_edge_does_not_lift_and_the_grab_fails(tmp_path):
    station, cell = _station(tmp_path, click_snap_radius_m=0.002)  # no snapping to the block's centre
    try:
        start = truth(station)
        yaw = BLOCK["yaw_rad"]
        edge_point = start + [EDGE_M / 2 * math.cos(yaw), EDGE_M / 2 * math.sin(yaw), EDGE_M / 2]  # middle of a top edge
        job = skills.grab(station, position_m=list(edge_point))
        assert job.wait(120)
        assert job.state == "failed" and "nothing in the gripper" in job.message, (job.state, job.message)
        assert cell.truth()["gripper"]["holding_id"] is None and station.held_block is None
        assert station.state is State.IDLE
        assert np.linalg.norm(truth(station) - start) < 0.005  # the block stays where it was
    finally:
        station.close()
        cell.close()
