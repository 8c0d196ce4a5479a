"""The station's PlanStore (armlab/station/plans.py): bounded (the oldest plan pushed out is unknown: 404), a plan
executes once (a second claim is refused as stale 'executed', even from 8 threads at once), an unclaimed send can be
retried, a discarded plan is unknown; and world_change names the first thing that changed."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.errors import PlanNotFound, PlanStale
from armlab.station.planned_moves import decimated_indices, world_change
from armlab.station.plans import MovePlan, PlanStore, new_plan_id

TRAJECTORY = JointTrajectory(np.array([0.0, 1.0]), np.zeros((2, 5)))


def _plan() -> MovePlan:
    return MovePlan(new_plan_id(), "move_joints", "pad", TRAJECTORY, np.zeros(5), "release", (0,), 100.0)


def test_the_store_keeps_the_newest_plans_only():
    store = PlanStore(capacity=16)
    plans = [store.add(_plan()) for _ in range(17)]
    assert len(store) == 16
    with pytest.raises(PlanNotFound, match="last 16"):
        store.get(plans[0].plan_id)
    assert store.get(plans[-1].plan_id) is plans[-1]


def test_a_plan_is_claimed_once_even_by_threads_at_once():
    store = PlanStore()
    plan = store.add(_plan())
    won, refused, barrier = [], [], threading.Barrier(8)

    def claim() -> None:
        barrier.wait()
        try:
            won.append(store.claim(plan.plan_id))
        except PlanStale as error:
            refused.append(error.reason)

    threads = [threading.Thread(target=claim) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(won) == 1 and refused == ["executed"] * 7
    store.unclaim(plan.plan_id)  # the send was refused after all: it may be executed
    assert store.claim(plan.plan_id) is plan
    store.discard(plan.plan_id)
    with pytest.raises(PlanNotFound):
        store.claim(plan.plan_id)
    with pytest.raises(PlanNotFound):
        store.discard(plan.plan_id)


def test_world_change_names_the_first_change():
    calibration = object()
    world = (3, 0, -np.inf, calibration, None, None, 100.0)
    assert world_change(world, world) is None
    assert world_change(world, (3, 0, -np.inf, calibration, None, None, 100.0)) is None
    assert world_change(world, (4, 0, -np.inf, calibration, None, None, 100.0))[1] == "arm_commanded"
    assert world_change(world, (3, 0, -np.inf, object(), None, None, 100.0))[1] == "calibration_changed"
    assert world_change(world, (3, 0, -np.inf, calibration, None, {"edge_m": 0.02}, 100.0))[1] == "gripper_changed"
    message, reason = world_change(world, (3, 0, -np.inf, calibration, None, None, 50.0))
    assert reason == "speed_changed" and "100 % to 50 %" in message


def test_decimation_keeps_both_ends():
    assert decimated_indices(10).tolist() == list(range(10))
    index = decimated_indices(1000, 60)
    assert len(index) == 60 and index[0] == 0 and index[-1] == 999
