"""The motion clock injected into the station (armlab/devices/clock.py, SimWorkcell.clock)."""

import threading

import pytest

from armlab.devices.clock import WallClock
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig


def test_the_wall_clock_waits_until_another_thread_makes_the_condition_true():
    clock, done = WallClock(), threading.Event()
    threading.Thread(target=lambda: (clock.wait_for(lambda: False, 0.05), done.set()), daemon=True).start()
    assert clock.wait_for(done.is_set, 30.0)  # true as soon as the other thread's own wait ended
    assert clock.wait_for(lambda: False, 0.01) is False  # and a condition that never holds times out false


def test_the_simulation_time_advances_the_fast_physics_while_it_is_waited_on():
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as cell:
        clock = cell.clock
        start_s = clock.now_s()
        assert start_s == cell.sim_time_s
        assert clock.wait_for(lambda: False, 0.2) is False
        assert clock.now_s() - start_s == pytest.approx(0.2, abs=cell.control_period_s + 1e-9)  # simulated, not wall, time
        assert clock.wait_for(lambda: cell.sim_time_s >= start_s + 0.3, 5.0)


def test_a_station_times_motion_on_the_simulation_clock_and_on_the_wall_clock_without_one(tmp_path):
    from armlab.kinematics import load_arm
    from armlab.station import Station, StationConfig

    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as cell:
        config = StationConfig(database_path=str(tmp_path / "db.sqlite3"))
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=config, sim=cell, synchronous=True)
        try:
            before_s = cell.sim_time_s
            assert station.clock_s() == before_s
            assert station.wait_motion(0.5)  # still: true at once, by the simulation's clock
            assert station.gate.wait_until(lambda: False, 0.25) is False  # a timeout of 0.25 simulated seconds ...
            assert cell.sim_time_s - before_s == pytest.approx(0.25, abs=0.06)  # ... advanced the physics that far
        finally:
            station.close()
        wall = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=config, sim=None)
        try:
            assert isinstance(wall.clock, WallClock)
        finally:
            wall.close()
