"""A station on the real arm in the fast simulation (realism real), its camera calibrated from the board tags and
then its arm from the camera, as a team does before its run: what the closed loops and the start check work on."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.workcell import load_workcell_arm


@contextlib.contextmanager
def calibrated_real_station(seed: int, scene: dict, folder: Path) -> Iterator[Station]:
    """A synchronous Station on rig `seed` with `scene`, its database in `folder`; camera and arm calibrated."""
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed, realism="real"), scene=Scene.from_dict(scene)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(), config=StationConfig(),
                          store=Store(folder / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        try:
            for calibrate in (skills.calibrate, skills.calibrate_arm):
                job = calibrate(station)
                assert job.wait(600) and job.state == "succeeded", job.message
            yield station
        finally:
            station.close()
