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
