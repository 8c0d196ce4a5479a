"""sort_by_tag and a block whose ArUco id has no destination in the workcell config: the job fails with a
message naming that block (its id, colour, size and where it is), after sorting what it can, and the
block stays where it was (ground truth). Real fast-mode simulation, real perception, synchronous station."""

from __future__ import annotations

import re

import numpy as np

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.tasks import start_auto

# id 42 is a valid DICT_4X4_250 marker that rx200_armlab's block_tags do not map to a place.
SCENE = {"objects": [
    {"id": "stray", "type": "block", "color": "green", "size": "large", "position_m": [0.12, 0.22, 0.019], "yaw_rad": 0.2,
     "aruco_id": 42},
]}


def test_a_tag_id_with_no_destination_fails_the_job_naming_the_block(tmp_path):
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=4), scene=Scene.from_dict(SCENE)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(),
                          store=Store(tmp_path / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        try:
            calibration = skills.calibrate(station)
            assert calibration.wait(60) and calibration.state == "succeeded", calibration.message
            job = start_auto(station, "sort_by_tag", 1)
            assert job.wait(120)
            assert job.state == "failed", f"{job.state}: {job.message}"
            assert "id 42" in job.message and "green large block" in job.message, job.message
            where = re.search(r"id 42 on the green large block at \((-?\d+), (-?\d+)\) mm", job.message)
            assert where and np.allclose([int(where[1]), int(where[2])], [120, 220], atol=10), job.message
            stray = next(o for o in cell.truth()["objects"] if o["id"] == "stray")
            assert np.allclose(stray["position_m"][:2], [0.12, 0.22], atol=0.005)  # left where it was
        finally:
            station.close()
