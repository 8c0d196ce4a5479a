"""Self-recalibration (calibration_trust.py) solves the camera pose with the intrinsics the station uses
(measured for this camera and accepted, else the camera's own), like the operator's tag calibration: with
the camera's own, a station that measured its intrinsics would silently fall back to the factory ones at
the first camera-moved recalibration (and report its calibration outdated again).

Fast-mode simulation, synchronous station, real SQLite; the measured intrinsics are stored under the
camera's key before start (as an accepted capture leaves them), 0.5 % off the camera's own so the two differ.
"""

from __future__ import annotations

import numpy as np

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.station import Station, StationConfig
from armlab.station.calibration_trust import SELF_RECALIBRATE_JOB, self_recalibration_job
from armlab.station.intrinsics import camera_key, intrinsics_dict
from armlab.store import Store


def run(job, cell):
    while job.state == "running":
        cell.step(0.05)
    assert job.state == "succeeded", job.message
    return job


def test_self_recalibration_uses_the_measured_intrinsics_in_use(tmp_path):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=3))
    cell.start()
    db = tmp_path / "station.sqlite3"
    try:
        own = cell.camera.intrinsics
        measured = {**intrinsics_dict(own), "fx": own.fx * 1.005, "fy": own.fy * 1.005}
        Store(db).save_intrinsics(camera_key(cell.camera, own), {"intrinsics": measured, "rms_px": 0.05, "views": 12})
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), sim=cell, synchronous=True,
                          config=StationConfig(database_path=str(db)))
        station.start()
        try:
            assert station.intrinsics.info()["source"] == "measured"
            run(skills.calibrate(station), cell)  # the operator's tag calibration: the measured intrinsics
            assert np.asarray(station.calibration.K)[0, 0] == measured["fx"]

            run(station.start_job("calibrate", SELF_RECALIBRATE_JOB, lambda ctx: self_recalibration_job(station, ctx)), cell)
            K = np.asarray(station.calibration.K)
            assert (K[0, 0], K[1, 1]) == (measured["fx"], measured["fy"]), f"self-recalibration solved with fx {K[0, 0]:.1f}"
            assert station.intrinsics.info(station.calibration)["calibration_outdated"] is False
        finally:
            station.close()
    finally:
        cell.close()
