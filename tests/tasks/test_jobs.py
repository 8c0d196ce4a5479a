"""Autonomous jobs on a real fast-mode simulation (synchronous station): a whole job scored by the
judge from ground truth, cancel and e-stop mid-job, bad requests that move nothing."""

from __future__ import annotations

import numpy as np
import pytest

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.errors import CommandRefused
from armlab.kinematics import load_arm
from armlab.scene import Scene
from armlab.station import State
from armlab.station.config import StationConfig
from armlab.station.core import NotCalibrated, Station
from armlab.store import Store
from armlab.tasks import JOBS, start_auto
from armlab.tasks.episode import run_episode

TWO_BLOCKS = {"objects": [
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.3},
    {"id": "blue", "type": "block", "color": "blue", "size": "small", "position_m": [-0.12, 0.20, 0.0125], "yaw_rad": -0.2},
]}


@pytest.fixture()
def station(calibrated_station):
    """A synchronous station on a fast-mode simulation of TWO_BLOCKS, calibrated."""
    return calibrated_station(TWO_BLOCKS)


def truth_by_id(station) -> dict:
    return {o["id"]: o for o in station.sim.truth()["objects"]}


def wait_until(job, predicate, timeout_s=120.0) -> bool:
    """Poll a job until predicate() or it ends (a condition wait; the job thread drives the physics)."""
    for _ in range(int(timeout_s / 0.01)):
        if predicate() or job.done:
            return predicate()
        job.done_event.wait(0.01)
    return predicate()


def test_pick_sort_level_1_scores_full_points_by_the_judge():
    result = run_episode("pick_sort", 1, 3)
    assert result["points"] == result["max_points"] == 100, result["breakdown"]
    assert result["within_limit"] and result["sim_time_s"] <= 180.0
    assert result["failures"] == []


def test_a_job_sorts_both_blocks_to_their_sides_in_ground_truth(station):
    job = start_auto(station, "pick_sort", 1)
    assert station.state is State.AUTO_SORT and station.status()["detail"] == "pick_sort L1"
    assert job.wait(300) and job.state == "succeeded", job.message
    truth = truth_by_id(station)
    assert truth["red"]["position_m"][1] < 0 and truth["red"]["position_m"][0] > 0  # large: x > 0
    assert truth["blue"]["position_m"][1] < 0 and truth["blue"]["position_m"][0] < 0  # small: x < 0
    assert station.state is State.IDLE
    task = job.to_dict()["extra"]["task"]
    assert task["done"] == 2 and task["left"] == 0 and task["moves"] == 2


def test_cancel_mid_job_puts_the_held_block_down_and_stops(station):
    job = start_auto(station, "pick_sort", 1)
    assert wait_until(job, lambda: station.sim.truth()["gripper"]["holding_id"] is not None), "never held a block"
    station.cancel_job()
    assert job.wait(120) and job.state == "cancelled", job.message
    assert station.state is State.IDLE
    assert station.sim.truth()["gripper"]["holding_id"] is None  # nothing left in the gripper
    held_down = [o for o in truth_by_id(station).values() if o["position_m"][2] < 0.03]
    assert len(held_down) == 2  # both blocks rest on the board
    q = station.joints_rad()
    station.sim.step(0.5)
    assert np.abs(station.joints_rad() - q).max() < 2e-3  # the arm does not move after the job


def test_estop_mid_job_halts_the_arm_and_latches(station):
    job = start_auto(station, "pick_sort", 1)
    # Holding lasts from the grasp to the release (the arm moving for most of it): a window the polling
    # thread cannot miss while the job thread drives the physics.
    assert wait_until(job, lambda: station.sim.truth()["gripper"]["holding_id"] is not None), "never held a block"
    station.estop()
    assert station.state is State.ESTOP
    assert job.wait(60) and job.state == "cancelled"
    assert not station.arm.is_moving()
    q = station.joints_rad()
    station.sim.step(0.5)
    assert np.abs(station.joints_rad() - q).max() < 5e-3
    with pytest.raises(CommandRefused):
        start_auto(station, "pick_sort", 1)


@pytest.mark.parametrize("job, level, params, error, match", [
    ("sort_everything", 1, None, ValueError, "unknown job"),
    ("pick_sort", 4, None, ValueError, "levels 1, 2, 3"),
    ("pick_sort", True, None, ValueError, "levels"),
    ("pick_sort", "2", None, ValueError, "levels"),
    ("pick_sort", 1, {"speed": 2}, ValueError, "no parameter"),
    ("pick_sort", 1, ["x"], ValueError, "params must be an object"),
    (5, 1, None, ValueError, "unknown job"),
])
def test_bad_requests_are_refused_and_nothing_moves(station, job, level, params, error, match):
    q = station.joints_rad()
    with pytest.raises(error, match=match):
        start_auto(station, job, level, params)
    assert station.state is State.IDLE
    station.sim.step(0.2)
    assert np.abs(station.joints_rad() - q).max() < 2e-3


def test_a_job_while_not_idle_is_refused(station):
    station.teach.start()
    with pytest.raises(CommandRefused) as refused:
        start_auto(station, "pick_sort", 1)
    assert "auto" not in refused.value.allowed
    assert station.state is State.TEACH
    station.estop()
    station.reset()


def test_a_job_needs_a_calibration(tmp_path):
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=5), scene=Scene.from_dict(TWO_BLOCKS)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(),
                          store=Store(tmp_path / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        with pytest.raises(NotCalibrated):
            start_auto(station, "pick_sort", 1)
        assert station.state is State.IDLE
        station.close()


def test_every_competition_event_has_a_job_with_its_levels():
    from armlab.scene.events import EVENTS

    for event, levels in EVENTS.items():
        assert event in JOBS, event
        assert JOBS[event].levels == tuple(levels)


def test_stale_detections_are_refused_after_the_arm_moved_over_them(station):
    blocks = skills.look(station)
    red = next(b for b in blocks if b.color == "red")
    assert not skills.is_stale(station, red)

    def sweep(ctx):
        q = station.model.ik([*red.position_m[:2], 0.12], q_seed=station.joints_rad())
        station.move_in_job(ctx, q)

    job = station.start_job("auto", "sweep", sweep)
    assert job.wait(60) and job.state == "succeeded", job.message
    assert skills.is_stale(station, red)  # the arm passed over it after it was seen
    fresh = next(b for b in skills.look(station) if b.color == "red")
    assert not skills.is_stale(station, fresh)
