"""A restored calibration passes its board-tag check on the perception thread just as the operator's own
calibration lands: the operator's (newer) calibration must stay in use. Before, the check decided
"still the restored candidate" under the lock, released it, and installed the restored calibration
afterwards, over the one the operator had installed in between.

The interleaving is made deterministic: the check reads its drift threshold from the perception config
between deciding and installing; a wrapper of the real config installs the operator's calibration at that
read (the thread switch of a real race). Fast-mode simulation, synchronous station, real calibrations.
"""

from __future__ import annotations

import time

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.station import Station, StationConfig
from armlab.station.calibration_trust import CalibrationTrust
from armlab.station.perception import Perception


class ConfigCalibratingMidCheck:
    """The station's perception config; the first read of `.calibration` runs `on_read` first."""

    def __init__(self, real, on_read) -> None:
        self._real, self._on_read = real, on_read

    def __getattr__(self, name):
        if name == "calibration" and self._on_read is not None:
            on_read, self._on_read = self._on_read, None
            on_read()
        return getattr(self._real, name)


def calibrated(station, cell):
    job = skills.calibrate(station)
    while job.state == "running":
        cell.step(0.05)
    assert job.state == "succeeded", job.message
    return station.calibration


def test_the_operators_calibration_is_not_replaced_by_a_restored_one_checked_meanwhile(tmp_path):
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=3))
    cell.start()
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), sim=cell, synchronous=True,
                      config=StationConfig(database_path=str(tmp_path / "station.sqlite3")))
    station.start()
    try:
        restored, operators = calibrated(station, cell), calibrated(station, cell)
        assert restored is not operators
        station.trust = CalibrationTrust(station.events, station.calibration_slot.publish, lambda: station.perception_config,
                                         station.config)  # the state after a restart: nothing in use...
        station.trust.restore_candidate(restored, {"calibrated": True}, time.time() - 1.0)  # ...the saved one a candidate
        assert station.trust.state == "checking"

        real = station.perception_config
        station.perception_config = ConfigCalibratingMidCheck(real, lambda: station.set_calibration(operators, {"method": "operator"}))
        station.trust.on_check(restored, 0.3, None, Perception(capture_time_s=time.time()))
        station.perception_config = real

        assert station.calibration is operators, "the restored calibration replaced the operator's newer one"
        assert station.calibration_info.get("method") == "operator" and station.trust.state == "trusted"
    finally:
        station.close()
        cell.close()
