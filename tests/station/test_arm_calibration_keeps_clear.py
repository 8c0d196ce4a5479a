"""The arm calibration (armlab.skills.calibrate_arm) on a board that was not cleared: it looks first and keeps its
moves clear of what stands there (raised, else skipped), so no block is knocked. Fast simulation of the real arm
(realism real, seed 1) on pick_sort L3 seed 1's scene, where the calibration's low poses used to tip two small
blocks over (one off a pile); truth from MuJoCo."""

from __future__ import annotations

import numpy as np
import pytest

from armlab import skills
from armlab.skills.arm_calibration import calibrate_arm

pytestmark = pytest.mark.slow


def _tilt_deg(quat_wxyz) -> float:
    w, x, y, z = quat_wxyz
    return float(np.degrees(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0))))


def test_the_arm_calibration_knocks_no_block(tmp_path):
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.station import Station, StationConfig
    from armlab.tasks.episode import episode_scene
    from armlab.workcell import load_workcell_arm

    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=1, realism="real"), scene=episode_scene("pick_sort", 3, 1)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(),
                          config=StationConfig(database_path=str(tmp_path / "station.sqlite3")), sim=cell, backend="sim", synchronous=True)
        station.start()
        try:
            tags = skills.calibrate(station)
            assert tags.wait(120) and tags.state == "succeeded", tags.message
            before = {o["id"]: o for o in cell.truth()["objects"]}
            job = calibrate_arm(station)
            assert job.wait(600) and job.state == "succeeded", job.message
            assert len(job.result["poses_used"]) >= 12
            for obj in cell.truth()["objects"]:
                moved_mm = 1000 * np.linalg.norm(np.subtract(obj["position_m"], before[obj["id"]]["position_m"]))
                assert moved_mm < 10.0 and _tilt_deg(obj["quat_wxyz"]) < 5.0, (obj["id"], moved_mm, _tilt_deg(obj["quat_wxyz"]))
        finally:
            station.close()
