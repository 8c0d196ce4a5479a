"""Helpers for the station's safety tests: a station on a simulated workcell with its own SQLite file, waits
on conditions (never fixed sleeps), a store whose writes announce themselves, a held database lock."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))
import live  # noqa: E402
from armlab.station import State  # noqa: E402

make_station = live.make_station  # the one test station builder (tests/server/live.py)

# A halted arm settles by a few mrad under gravity; a move that kept going would travel ~0.1 rad or more.
HALT_TOL_RAD = 5e-3
FAR_Q = np.array([0.8, 0.3, 0.2, 0.4, 0.5])


def joints(station) -> np.ndarray:
    return np.asarray(station.arm.read_joint_state().position_rad, dtype=float)


def wait_sim(cell, duration_s: float, timeout_s: float = 30.0) -> None:
    """Wait (a condition on the simulated clock, not a fixed sleep) until duration_s of sim time passed."""
    start = cell.sim_time_s
    live.wait_for(lambda: cell.sim_time_s >= start + duration_s, timeout_s, 0.005)


def wait_moving(station, timeout_s: float = 10.0) -> None:
    """Until the arm measurably moves (joint speed > 0.05 rad/s)."""
    live.wait_for(lambda: np.linalg.norm(station.arm.read_joint_state().velocity_rad_s) > 0.05, timeout_s, 0.005)


def back_to_idle(station) -> None:
    """E-stop + reset if needed, wait for the job to end and the arm to stop."""
    job = station.current_job()
    if station.state is not State.IDLE:
        station.estop()
        station.reset()
    if job is not None:
        job.wait(10)
    live.wait_for(lambda: not station.arm.is_moving(), 10)


def at_rest(station, q) -> None:
    """The station idle (e-stopped and reset if it was not) with the arm at rest at joints q."""
    if station.state.value != "idle":
        station.estop()
        station.reset()
    station.move_joints(q, wait=True)
    station.wait_motion(5.0)


def still_for(cell, station, duration_s: float, tol_rad: float = HALT_TOL_RAD) -> bool:
    """True if the arm's joints stay within tol_rad of where they are now for duration_s of sim time."""
    q0 = joints(station)
    worst = 0.0
    start = cell.sim_time_s
    while cell.sim_time_s < start + duration_s:
        worst = max(worst, float(np.abs(joints(station) - q0).max()))
        wait_sim(cell, 0.02)
    return worst < tol_rad


class SignallingStore:
    """Factory of a real Store whose writes announce themselves: `writing` is set when a write begins
    (the write itself is the real SQLite one, so a locked database really blocks it)."""

    @staticmethod
    def make(path):
        import threading

        from armlab.store import Store

        class _Store(Store):
            def __init__(self, *args, **kwargs) -> None:
                super().__init__(*args, **kwargs)
                self.writing = threading.Event()

            def save_program(self, *args, **kwargs):
                self.writing.set()
                return super().save_program(*args, **kwargs)

            def save_calibration(self, *args, **kwargs):
                self.writing.set()
                return super().save_calibration(*args, **kwargs)

        return _Store(path)


class DatabaseLock:
    """Hold SQLite's write lock on `path` from another connection (another process would do the same):
    every write of the station blocks until release() (or SQLite's 5 s busy timeout)."""

    def __init__(self, path) -> None:
        import sqlite3

        self._connection = sqlite3.connect(str(path), timeout=0, isolation_level=None)
        self._connection.execute("BEGIN EXCLUSIVE")

    def release(self) -> None:
        self._connection.execute("ROLLBACK")
        self._connection.close()


