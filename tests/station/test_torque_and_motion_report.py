"""Torque off while idle (issue 10 item 9): refused outside teach unless confirmed; and when the arm does
move without a trajectory (limp, falling under gravity), status says so from the measured velocity."""

from __future__ import annotations

import numpy as np
import pytest

import live
from armlab.errors import NeedsConfirmation
from armlab.station import State
from station_helpers import back_to_idle, make_station, still_for

RAISED_Q = np.array([0.0, 0.2, 0.3, 0.0, 0.0])  # forearm out: it falls when limp


@pytest.fixture(scope="module")
def station(cell, db_path):
    station = make_station(cell, db_path)
    yield station
    station.close()


@pytest.fixture()
def raised(station):
    back_to_idle(station)
    station.set_torque(True)
    station.move_joints(RAISED_Q, moving_time_s=0.8, wait=True)
    yield station
    back_to_idle(station)
    station.set_torque(True)
    station.move_joints(station.model.home_rad, moving_time_s=1.5, wait=True)


def test_torque_off_outside_teach_needs_confirmation_and_changes_nothing(cell, raised):
    station = raised
    with pytest.raises(NeedsConfirmation, match="confirm"):
        station.set_torque(False)
    assert still_for(cell, station, 0.5), "the arm sagged: torque went off anyway"
    assert station.state is State.IDLE


def test_a_limp_arm_falling_is_reported_as_moving(cell, raised):
    station = raised
    q0 = station.joints_rad()
    station.set_torque(False, confirm=True)
    moving = live.wait_for(lambda: station.status()["moving"] and not station.arm.is_moving(), 5, 0.005)
    assert moving
    live.wait_for(lambda: np.abs(station.joints_rad() - q0).max() > 0.05, 5, 0.005)  # it really fell
    station.set_torque(True)
    live.wait_for(lambda: not station.status()["moving"], 10)


def test_torque_off_in_teach_needs_no_confirmation(cell, raised):
    station = raised
    station.teach.start()
    station.set_torque(False)
    live.wait_for(lambda: station.status()["moving"], 5, 0.005)
    station.set_torque(True)
    station.teach.record()  # the pose it was moved (fell) to by hand
    station.teach.stop("limp teach")
    assert station.state is State.IDLE
