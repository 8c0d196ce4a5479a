"""Faults that must not stay silent (issue 20 item 6): a teach recorder thread that dies on a damaged database, the
simulation's physics thread dying, and the station lock never held across a slow device call (status and
telemetry answer while the arm's command is in progress; the e-stop still wins). Failures are injected: the
database file really damaged, the physics step raising, an arm whose calls wait on an Event the test holds."""

from __future__ import annotations

import logging
import os
import threading

import numpy as np
import pytest

import live
from armlab.errors import CommandRefused, DeviceLost
from armlab.kinematics import load_arm
from armlab.station import State, Station, StationConfig
from station_helpers import FAR_Q, HALT_TOL_RAD, back_to_idle, joints, make_station, still_for

WAIT_S = 10.0  # generous bound on a condition that holds within a few device checks (never a timing assert)


def _events(station) -> list[str]:
    return [event["message"] for event in station.events.since(0)]


def _in_thread(function) -> tuple[threading.Event, dict]:
    """Run function() on a thread; (done event, {"result" | "error": ...})."""
    done, out = threading.Event(), {}

    def run() -> None:
        try:
            out["result"] = function()
        except BaseException as error:  # noqa: BLE001 - handed to the test
            out["error"] = error
        done.set()

    threading.Thread(target=run, daemon=True).start()
    return done, out


# ------------------------------------------------------------------------------------------ teach recorder


def test_a_teach_recorder_dying_on_a_damaged_database_faults_the_station_and_halts_the_arm(cell, tmp_path, caplog):
    path = tmp_path / "teach.sqlite3"
    station = make_station(cell, path)
    try:
        back_to_idle(station)
        station.teach.start(discard_draft=True)
        recorder = station.teach.continuous(20.0)
        station.move_joints(FAR_Q, moving_time_s=4.0)
        live.wait_for(lambda: recorder.recorded >= 2, WAIT_S)
        # The database file is damaged under the running station (its WAL too): the next record raises
        # sqlite3.DatabaseError, which the recorder used to die on without a word, the arm moving on.
        garbage = tmp_path / "garbage"
        garbage.write_bytes(b"this is not an SQLite database" * 200)
        os.replace(garbage, path)
        for suffix in ("-wal", "-shm"):
            if os.path.exists(f"{path}{suffix}"):
                os.unlink(f"{path}{suffix}")
        live.wait_for(lambda: station.state is State.FAULT, WAIT_S)
        status = station.status()
        assert status["state"] == "fault"
        assert "teach recorder failed" in status["detail"] and "DatabaseError" in status["detail"]
        assert any("teach recorder failed" in message for message in _events(station))
        assert any("teach recorder" in record.getMessage() and record.levelno >= logging.ERROR for record in caplog.records)
        live.wait_for(lambda: not recorder.is_alive(), WAIT_S)  # it faults the station, then returns
        assert "DatabaseError" in recorder.error
        live.wait_for(lambda: not station.arm.is_moving(), WAIT_S)
        assert np.abs(joints(station) - FAR_Q).max() > 0.05  # halted on the way, not left to finish the move
        assert still_for(cell, station, 0.3)
        with pytest.raises(CommandRefused):
            station.move_joints(station.model.home_rad)
    finally:
        station.close()
    live.wait_for(lambda: not cell.arm.is_moving(), WAIT_S)


# ------------------------------------------------------------------------------------ the lock and the arm


class SlowArm:
    """The simulated arm, whose command_trajectory and set_torque wait until the test lets them through (as a
    ROS service call that takes its time would): `entered` is set once one is in progress, `release` lets it go.
    Everything else is the real arm's."""

    def __init__(self, arm) -> None:
        self._arm = arm
        self.entered, self.release = threading.Event(), threading.Event()

    def __getattr__(self, name):
        return getattr(self._arm, name)

    def __str__(self) -> str:
        return str(self._arm)

    def _wait_for_release(self) -> None:
        self.entered.set()
        assert self.release.wait(60.0)

    def command_trajectory(self, trajectory, wait: bool = False, start_time_s: float | None = None) -> float:
        self._wait_for_release()
        return self._arm.command_trajectory(trajectory, wait, start_time_s)

    def set_torque(self, enabled: bool) -> None:
        self._wait_for_release()
        self._arm.set_torque(enabled)


def test_status_and_telemetry_answer_while_the_arms_call_is_in_progress_and_the_estop_still_wins(cell, tmp_path):
    slow = SlowArm(cell.arm)
    station = Station(slow, cell.gripper, cell.camera, model=load_arm("rx200"), sim=cell, backend="sim",
                      config=StationConfig(database_path=str(tmp_path / "slow.sqlite3")))
    station.start()
    try:
        slow.release.set()
        back_to_idle(station)
        slow.release.clear()
        q_start = joints(station)
        moved, move = _in_thread(lambda: station.move_joints(FAR_Q, moving_time_s=2.0))
        assert slow.entered.wait(WAIT_S)
        # The trajectory is on its way to the arm: the station still answers (before: status, telemetry and
        # the allowed commands waited on the lock the move held across the call).
        answered, answer = _in_thread(lambda: (station.status(), station.telemetry_snapshot(), station.allowed_commands()))
        assert answered.wait(WAIT_S), "status waited for the arm's command_trajectory"
        assert answer["result"][0]["state"] == "idle"
        estopped, _ = _in_thread(station.estop)
        assert estopped.wait(WAIT_S), "e-stop waited for the arm's command_trajectory"
        assert station.state is State.ESTOP
        slow.release.set()  # the trajectory reaches the arm after the e-stop: the sender halts it again
        assert moved.wait(WAIT_S) and "error" not in move
        live.wait_for(lambda: not station.arm.is_moving(), WAIT_S)
        assert np.abs(joints(station) - q_start).max() < 2 * HALT_TOL_RAD
        assert still_for(cell, station, 0.3)

        station.reset()
        slow.entered.clear()
        slow.release.clear()
        torqued, torque = _in_thread(lambda: station.set_torque(False, confirm=True))
        assert slow.entered.wait(WAIT_S)
        answered, answer = _in_thread(station.status)
        assert answered.wait(WAIT_S), "status waited for the arm's set_torque"
        assert answer["result"]["torque_enabled"] is True  # not yet: the call has not gone through
        slow.release.set()
        assert torqued.wait(WAIT_S) and "error" not in torque
        assert station.status()["torque_enabled"] is False
        station.set_torque(True)
        assert station.status()["torque_enabled"] is True
    finally:
        slow.release.set()
        station.close()


# ------------------------------------------------------------------------------------------- sim physics


def test_the_simulations_physics_thread_dying_is_a_device_fault(tmp_path, caplog):
    cell = live.start_cell(seed=3)
    station = make_station(cell, tmp_path / "physics.sqlite3", device_check_rate_hz=10.0)
    try:
        station.move_joints(FAR_Q, moving_time_s=3.0)
        live.wait_for(lambda: station.arm.is_moving(), WAIT_S)
        step = cell._step_once

        def failing_step() -> None:  # the injected failure: one physics step raises
            raise FloatingPointError("injected: MuJoCo step failed")

        cell._step_once = failing_step
        live.wait_for(lambda: station.state is State.FAULT, WAIT_S)  # before: reads kept succeeding, no fault
        cell._step_once = step  # the thread is gone: putting the step back does not revive it
        status = station.status()
        assert status["state"] == "fault" and "physics" in status["detail"] and "injected" in status["detail"]
        assert "arm" in status["devices_lost"]
        assert any("lost" in message and "physics" in message for message in _events(station))
        assert any("physics thread died" in record.getMessage() for record in caplog.records)
        with pytest.raises(DeviceLost, match="physics"):
            station.reset()
        with pytest.raises(CommandRefused):
            station.move_joints(station.model.home_rad)
    finally:
        station.close()
        cell.close()
