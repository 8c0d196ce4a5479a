"""Shared fixtures of the job tests."""

from __future__ import annotations

import contextlib

import pytest

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store


@pytest.fixture()
def calibrated_station(tmp_path):
    """make(scene, seed) -> a synchronous, calibrated RX200 station on a fast-mode simulation of `scene` (a Scene
    or its dict); closed with its simulation after the test."""
    with contextlib.ExitStack() as stack:

        def make(scene, seed: int = 5) -> Station:
            scene = scene if isinstance(scene, Scene) else Scene.from_dict(scene)
            cell = stack.enter_context(SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed), scene=scene))
            station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(),
                              store=Store(tmp_path / f"s{seed}.sqlite3"), sim=cell, synchronous=True)
            station.start()
            stack.callback(station.close)
            job = skills.calibrate(station)
            assert job.wait(60) and job.state == "succeeded", job.message
            return station

        yield make
