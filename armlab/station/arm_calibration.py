"""The arm's calibration held by the station (issue 19 item 2): installed into the station's one arm model
(Station.model, a CalibratedArm) so every motion plans with it, saved in the database beside the camera's
calibration, restored at start when it was made for this arm and workcell (a different arm, workcell or base
pose: not restored, a warning says why), and reported in the status as {calibrated, residual_mm, at}."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from armlab.kinematics.arm_calibration import ArmCalibration, ArmCalibrationError


class ArmCalibrationKeeper:
    """Station part (station.arm_calibration): the arm calibration in use, its summary, save and restore.

    model: the station's arm model (a CalibratedArm; None or a bare ArmModel: nothing to calibrate); store: the
    database; events: the event log; workcell: the station's workcell name (part of what a calibration belongs to)."""

    def __init__(self, model: Any, store: Any, events: Any, workcell: str | None) -> None:
        self._model, self._store, self._events, self._workcell = model, store, events, workcell
        self._info: dict | None = None  # the summary of the calibration in use (None: none installed)

    @property
    def info(self) -> dict | None:
        """The summary saved with the calibration in use ({residual_mm, at, ...}), None before one was installed."""
        return self._info

    def rig_key(self) -> dict:
        """What an arm calibration belongs to: the arm, the workcell and the nominal base pose."""
        nominal = getattr(self._model, "nominal", self._model)
        return {"arm": nominal.name, "workcell": self._workcell, "dof": int(nominal.dof),
                "T_world_base": np.asarray(nominal.T_world_base, float).round(6).tolist()}

    @property
    def status(self) -> dict:
        """GET /api/status `arm_calibration`: {calibrated, residual_mm, at} (residual: the fit's mean, mm)."""
        info = self._info
        if info is None or getattr(self._model, "calibration", None) is None:
            return {"calibrated": False, "residual_mm": None, "at": None}
        return {"calibrated": True, "residual_mm": info.get("residual_mm"), "at": info.get("at")}

    def install(self, calibration: ArmCalibration, info: dict, save: bool = True) -> None:
        """Use this calibration for every motion from now on (and save it with info, unless restoring)."""
        if not hasattr(self._model, "set_calibration"):
            raise ArmCalibrationError("this station has no arm model to calibrate")
        info = {**info, "residual_mm": round(calibration.residual_mm, 3), "at": info.get("at", time.time())}
        if save:
            self._store.save_arm_calibration({"calibration": calibration.to_dict(), "info": info, "rig": self.rig_key()})
        self._model.set_calibration(calibration)
        self._info = info

    def restore(self) -> None:
        """The newest saved arm calibration, if it was made for this arm, workcell and base pose."""
        if self._model is None or not hasattr(self._model, "set_calibration"):
            return
        data = self._store.latest_arm_calibration()
        if data is None:
            return
        rig = data.get("rig")
        if rig != self.rig_key():
            self._events.add("warn", f"saved arm calibration not restored: it was made for {_rig_text(rig)}, this is "
                                     f"{_rig_text(self.rig_key())} (calibrate the arm again)")
            return
        try:
            calibration = ArmCalibration.from_dict(data["calibration"], self._model.dof)
            info = dict(data["info"])
        except (KeyError, TypeError, ValueError) as error:
            self._events.add("warn", f"saved arm calibration not restored: {error}")
            return
        self.install(calibration, {**info, "restored": True}, save=False)
        self._events.add("info", f"saved arm calibration restored (residual {calibration.residual_mm:.2f} mm)")


def _rig_text(rig: Any) -> str:
    if not isinstance(rig, dict):
        return "an unknown rig"
    return f"arm {rig.get('arm')} in workcell {rig.get('workcell')}"
