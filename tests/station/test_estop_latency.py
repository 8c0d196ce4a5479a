"""E-stop is never slower than the slowest lock (issue 10 item 4): the latch is set first, the arm is halted
outside the station lock, and no I/O runs under that lock. Each load below is really blocked (a SQLite write
lock held by another connection, a scene whose objects arrive slowly, the station lock itself held) and the
e-stop must answer and halt the arm *while the load is still blocked*. The halt is measured in simulated
time: from the stop request to the control tick that applied it, at most one control period.
Wall-clock figures are in bench/estop.py."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import live
from armlab import skills
from armlab.scene import Scene, SceneObject
from armlab.station import State
from armlab.station.states import JOB_STATES
from station_helpers import FAR_Q, DatabaseLock, SignallingStore, back_to_idle, make_station, still_for, wait_moving

JOB_COMMAND = {State.CALIBRATE: "calibrate", State.REPEAT: "repeat", State.CLICK_GRAB: "grab", State.CLICK_DROP: "drop", State.AUTO_SORT: "auto"}
BLOCKED_WAIT_S = 3.0  # hang detector: the load stays blocked longer than this (SQLite's busy timeout is 5 s)


@pytest.fixture(scope="module")
def station(cell, db_path):
    station = make_station(cell, db_path, store=SignallingStore.make(db_path))
    yield station
    station.close()


@pytest.fixture()
def idle(station):
    back_to_idle(station)
    station.store.writing.clear()
    station.move_joints(station.model.home_rad, moving_time_s=0.5, wait=True)
    yield station
    back_to_idle(station)


def _estop_in_thread(station) -> threading.Event:
    done = threading.Event()

    def press() -> None:
        station.estop(source="test")
        done.set()

    threading.Thread(target=press, daemon=True).start()
    return done


def _halted_within_a_control_period(cell, since_sim_s: float) -> None:
    """The arm's halt requested after since_sim_s was applied within one control period of sim time. (When
    the workcell's lock is busy the halt is applied by the next control tick, possibly just after estop()
    returns: wait for that tick's record.)"""
    live.wait_for(lambda: (cell.arm.last_halt_sim_s or (-1.0, -1.0))[1] >= since_sim_s, BLOCKED_WAIT_S, 0.001)
    requested_s, applied_s = cell.arm.last_halt_sim_s
    assert applied_s - requested_s <= cell.control_period_s + 1e-9, f"halt took {applied_s - requested_s:.4f} s of sim time"


def _long_move(station, state: State) -> None:
    """The arm moving (a 10 s move) in `state`."""
    if state is State.TEACH:
        station.teach.start()
    if state in (State.IDLE, State.TEACH):
        station.move_joints(FAR_Q, moving_time_s=10.0)
    else:
        station.start_job(JOB_COMMAND[state], "long move", lambda ctx: station.move_in_job(ctx, FAR_Q, moving_time_s=10.0))
    wait_moving(station)
    assert station.state is state


@pytest.mark.parametrize("state", list(State), ids=lambda s: s.value)
def test_estop_from_every_state_halts_within_one_control_period(cell, idle, state):
    station = idle
    if state is State.FAULT:
        station.start_job("auto", "broken", lambda ctx: (_ for _ in ()).throw(ConnectionError("servo bus lost"))).wait(5)
    elif state is State.ESTOP:
        station.estop()
    else:
        _long_move(station, state)
    assert station.state is state
    t0 = cell.sim_time_s
    station.estop(source="test")
    assert station.state is State.ESTOP
    _halted_within_a_control_period(cell, t0)
    assert not station.arm.is_moving()
    assert still_for(cell, station, 0.3)


def test_estop_halts_while_another_thread_holds_the_station_lock(cell, idle):
    """White-box: whatever holds the station's lock (a slow command), the halt does not wait for it."""
    station = idle
    _long_move(station, State.IDLE)
    t0 = cell.sim_time_s
    with station._lock:  # noqa: SLF001 - the lock every command takes
        done = _estop_in_thread(station)
        live.wait_for(lambda: cell.arm.last_halt_sim_s is not None and cell.arm.last_halt_sim_s[1] >= t0, BLOCKED_WAIT_S, 0.005)
        assert not station.arm.is_moving()
        q_halted = station.joints_rad()
    assert done.wait(BLOCKED_WAIT_S)
    _halted_within_a_control_period(cell, t0)
    assert station.state is State.ESTOP
    assert np.abs(station.joints_rad() - q_halted).max() < 5e-3


def test_estop_answers_during_a_blocked_sqlite_write(cell, db_path, idle):
    """teach_stop's program write waits on a locked database: the e-stop neither waits for it nor loses it."""
    station = idle
    _long_move(station, State.TEACH)
    station.teach.record()
    lock = DatabaseLock(db_path)
    saved: dict = {}
    saver = threading.Thread(target=lambda: saved.update(program=station.teach.stop("saved under e-stop")), daemon=True)
    try:
        saver.start()
        assert station.store.writing.wait(BLOCKED_WAIT_S)
        t0 = cell.sim_time_s
        done = _estop_in_thread(station)
        answered = done.wait(BLOCKED_WAIT_S)
        still_blocked = saver.is_alive()
    finally:
        lock.release()
    assert answered and still_blocked, "the e-stop waited for the SQLite write"
    _halted_within_a_control_period(cell, t0)
    saver.join(10)
    assert station.state is State.ESTOP
    # What the API acknowledged (the returned program) is on disk.
    assert saved["program"].name in [program.name for program in station.store.list_programs()]


def test_a_job_starts_without_waiting_for_a_locked_database(cell, db_path, idle):
    """Starting a job (an HTTP request's thread) never waits on SQLite: the job's history row is written by the
    job's own thread (a locked database held the caller for the 5 s busy timeout, and under load the job's own
    save timed out before the caller got back)."""
    station = idle
    lock = DatabaseLock(db_path)
    started, box = threading.Event(), {}
    try:
        threading.Thread(target=lambda: (box.update(job=station.start_job("auto", "quick", lambda ctx: "done")), started.set()),
                         daemon=True).start()
        answered = started.wait(BLOCKED_WAIT_S)
    finally:
        lock.release()
    assert answered, "starting a job waited for the locked database"
    job = box["job"]
    assert job.wait(10) and job.state == "succeeded", job.message
    live.wait_for(lambda: any(row["id"] == job.id for row in station.store.job_results()), 10)


def test_estop_answers_during_a_calibration_write(cell, db_path, idle):
    station = idle
    cell.set_scene(Scene())
    lock = DatabaseLock(db_path)
    try:
        job = skills.calibrate(station)
        assert station.store.writing.wait(20), job.message
        assert station.state is State.CALIBRATE
        t0 = cell.sim_time_s
        answered = _estop_in_thread(station).wait(BLOCKED_WAIT_S)
        still_blocked = not job.done
    finally:
        lock.release()
    assert answered and still_blocked
    _halted_within_a_control_period(cell, t0)
    assert job.wait(10) and station.state is State.ESTOP


class _SlowObjects(tuple):
    """A scene's object list that arrives only once `ready` is set (a slow scene source)."""

    ready: threading.Event
    reading: threading.Event

    def __iter__(self):
        self.reading.set()
        self.ready.wait(30)
        return super().__iter__()


def test_estop_answers_during_a_scene_change(cell, idle):
    station = idle
    _long_move(station, State.IDLE)
    objects = _SlowObjects([SceneObject(id="b", type="block", color="red", size="large", position_m=(0.1, 0.25, 0.019))])
    objects.ready, objects.reading = threading.Event(), threading.Event()
    scene = Scene()
    object.__setattr__(scene, "objects", objects)
    changer = threading.Thread(target=lambda: station.set_scene(scene, source="test"), daemon=True)
    try:
        changer.start()
        assert objects.reading.wait(BLOCKED_WAIT_S)
        t0 = cell.sim_time_s
        done = _estop_in_thread(station)
        answered = done.wait(BLOCKED_WAIT_S)
        status = station.status() if answered else None
    finally:
        objects.ready.set()
    changer.join(30)
    assert answered, "the e-stop waited for the scene change"
    assert status["state"] == "estop"
    _halted_within_a_control_period(cell, t0)
    assert [obj["id"] for obj in cell.truth()["objects"]] == ["b"]


def test_no_trajectory_reaches_the_arm_after_the_latch(cell, idle):
    """A job that tries to move after the e-stop is refused by the latch (its job is cancelled)."""
    station = idle
    go = threading.Event()
    outcome: dict = {}

    def job(ctx):
        go.wait(10)
        try:
            station.move_in_job(ctx, FAR_Q, moving_time_s=2.0)
        except BaseException as error:  # noqa: BLE001 - recorded for the assertion
            outcome["error"] = error
            raise

    running = station.start_job("auto", "late mover", job)
    station.estop()
    go.set()
    assert running.wait(10)
    assert type(outcome["error"]).__name__ == "JobCancelled"
    assert still_for(cell, station, 0.3)


def test_job_states_are_the_ones_with_a_job():
    assert set(JOB_COMMAND) == set(JOB_STATES)
