"""Issue 21, the reach overlay on the UR3 suction workcell: the station's reach map (the grid the page draws) marks the
far edge of the suction cup's top-down region reachable, and a grab there lifts the block with the cup pointing
straight down; a cell it marks out of reach is refused before anything moves. Fast-mode simulation, synchronous
station, ground truth from the simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.errors import PLAN_REFUSALS
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.workcell import load_workcell, load_workcell_arm

WORKCELL = "ur3_suction"
EDGE_M = load_workcell(WORKCELL).block_edge_m("large")


def _interior_cell(reach: dict, letter: str, near_m) -> tuple[float, float]:
    """The centre of the `letter` cell nearest near_m whose 8 neighbours have it too."""
    best = None
    for j in range(1, reach["ny"] - 1):
        for i in range(1, reach["nx"] - 1):
            if all(reach["rows"][j + dj][i + di] == letter for dj in (-1, 0, 1) for di in (-1, 0, 1)):
                x, y = reach["x0_m"] + i * reach["step_m"], reach["y0_m"] + j * reach["step_m"]
                if best is None or math.dist((x, y), near_m) < best[0]:
                    best = (math.dist((x, y), near_m), (x, y))
    assert best is not None, f"no interior '{letter}' cell"
    return best[1]


@pytest.fixture(scope="module")
def ur3(tmp_path_factory):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=4, workcell=WORKCELL), scene=Scene.from_dict({"objects": []}))
    cell.start()
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(WORKCELL),
                      config=StationConfig(workcell=WORKCELL),
                      store=Store(tmp_path_factory.mktemp("ur3reach") / "s.sqlite3"), sim=cell, synchronous=True)
    station.start()
    job = skills.calibrate(station)
    assert job.wait(60) and job.state == "succeeded", job.message
    yield station, cell
    station.close()
    cell.close()


def test_the_ur3_reach_map_is_what_the_suction_grab_does(ur3):
    station, cell = ur3
    reach = station.reach.get(station)
    assert set("".join(reach["rows"])) <= {"T", "."}  # a suction cup works top-down only
    x, y = _interior_cell(reach, "T", (0.0, 0.6))  # the far edge of the top-down region
    cell.set_scene(Scene.from_dict({"objects": [
        {"id": "b1", "type": "block", "color": "yellow", "size": "large", "position_m": [x, y, EDGE_M / 2], "yaw_rad": 0.0,
         "aruco_id": 100}]}))
    station.fresh_perception()
    cell.start_joint_recording()
    job = skills.grab(station, position_m=[x, y, EDGE_M])
    assert job.wait(120) and job.state == "succeeded", job.message
    trace = cell.stop_joint_recording()
    assert cell.truth()["gripper"]["holding_id"] == "b1"
    frames = np.asarray(station.model.fk(np.asarray(trace["position_rad"])))
    lowest = int(np.argmin(frames[:, 2, 3]))
    tilt_deg = math.degrees(math.acos(max(-1.0, min(1.0, -float(frames[lowest, 2, 0])))))
    assert tilt_deg < 3.0, f"the cup was {tilt_deg:.1f}° off vertical at ({x:.3f}, {y:.3f}) m"

    job = skills.drop(station, position_m=[x, y, 0.0])
    assert job.wait(120), job.message
    corner = (reach["x0_m"], reach["y0_m"] + (reach["ny"] - 1) * reach["step_m"])
    assert reach["rows"][-1][0] == "."
    before = station.joints_rad()
    with pytest.raises(PLAN_REFUSALS):
        skills.grab(station, position_m=[*corner, EDGE_M])
    assert np.max(np.abs(station.joints_rad() - before)) < 5e-3
