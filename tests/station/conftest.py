"""Fixtures for the station's safety tests: a real-time simulated workcell per module and a database path."""

from __future__ import annotations

import pytest

from station_helpers import live


@pytest.fixture(scope="module")
def cell():
    cell = live.start_cell(seed=7)
    yield cell
    cell.close()


@pytest.fixture(scope="module")
def db_path(tmp_path_factory):
    return tmp_path_factory.mktemp("station") / "station.sqlite3"


@pytest.fixture(scope="module")
def fast(tmp_path_factory):
    """A fast (not real-time), synchronous simulated RX200 station for one module: (station, cell), seed 0;
    motion measured on the simulation's clock, so figures do not depend on the machine's load."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.station import Station, StationConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=0))
    cell.start()
    db = tmp_path_factory.mktemp("fast") / "station.sqlite3"
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(database_path=str(db)),
                      sim=cell, backend="sim", synchronous=True)
    station.start()
    yield station, cell
    station.close()
    cell.close()
