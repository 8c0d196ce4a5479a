"""The arm calibration as a part (station.arm_calibration, arm_calibration.py), built without a Station: a real
CalibratedArm of the RX200, a real SQLite store and event log. Installed, it corrects the model every planner uses
and is saved; restored, only for the same arm, workcell and base pose; its status says what is in use."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.kinematics.arm_calibration import ArmCalibration, ArmCalibrationError
from armlab.kinematics.calibrated_arm import CalibratedArm
from armlab.station.arm_calibration import ArmCalibrationKeeper
from armlab.station.slots import EventLog
from armlab.store import Store

Q = np.array([0.3, -0.2, 0.4, 0.5, 0.1])


def _fit() -> ArmCalibration:
    """A fit with a 20 mrad waist offset and a 4 mm base shift, residual 1.5 mm."""
    return ArmCalibration(joint_offset_rad=np.array([0.02, 0.0, 0.0, 0.0, 0.0]), compliance_rad_per_nm=np.zeros(5),
                          servo_compliance_rad_per_nm=np.zeros(5), base_correction=np.array([0.004, 0.0, 0.0, 0.0, 0.0, 0.0]),
                          residuals_before_m=np.array([0.008]), residuals_after_m=np.array([0.0015]))


@pytest.fixture()
def store(tmp_path):
    return Store(str(tmp_path / "station.sqlite3"), backups=0)


def _keeper(store, workcell="rx200_armlab"):
    """(the part, the model it corrects, its event log)."""
    model, events = CalibratedArm(load_arm("rx200")), EventLog()
    return ArmCalibrationKeeper(model, store, events, workcell), model, events


def test_installed_it_moves_the_models_gripper_point_and_is_saved_and_reported(store):
    keeper, model, _ = _keeper(store)
    nominal_m = model.fk(Q)[:3, 3].copy()
    assert keeper.status == {"calibrated": False, "residual_mm": None, "at": None}
    keeper.install(_fit(), {"poses_used": 12, "at": 1000.0})
    moved_mm = 1000.0 * np.linalg.norm(model.fk(Q)[:3, 3] - nominal_m)
    assert moved_mm > 1.0  # the offsets and the base shift change where the one model planners use puts the gripper
    assert keeper.status == {"calibrated": True, "residual_mm": 1.5, "at": 1000.0}
    assert store.latest_arm_calibration()["rig"]["arm"] == "rx200"


def test_restored_only_for_the_same_arm_and_workcell(store):
    _keeper(store)[0].install(_fit(), {"at": 1000.0})
    same, model, _ = _keeper(store)
    same.restore()
    assert same.status["calibrated"] and same.info["restored"] is True and model.calibration is not None
    other, model, events = _keeper(store, workcell="another_cell")
    other.restore()
    assert not other.status["calibrated"] and model.calibration is None
    assert "not restored" in events.since(0)[-1]["message"]


def test_a_station_without_an_arm_model_to_calibrate_refuses(store):
    keeper = ArmCalibrationKeeper(load_arm("rx200"), store, EventLog(), "rx200_armlab")  # a bare model: nothing to correct
    with pytest.raises(ArmCalibrationError):
        keeper.install(_fit(), {})
    keeper.restore()  # nothing to restore into: no error
    assert keeper.status["calibrated"] is False
