"""StationClient.auto / auto_jobs / auto_score against a real server (uvicorn on a free port) on the
real-time simulation."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent / "server"))
import live  # noqa: E402
from armlab.client import StationClient, StationError  # noqa: E402

TOKEN = "client-auto-token"
ONE_BLOCK = [{"id": "r", "type": "block", "color": "red", "size": "large", "position_m": [0.08, 0.24, 0.019], "yaw_rad": 0.3}]


cell, url = live.module_fixtures(seed=4, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture()
def station(url):
    with StationClient(url, TOKEN) as client:
        yield client
        state = client.status()["state"]
        if state == "auto_sort":
            client.cancel_job()
            client.wait_job(60)
        elif state != "idle":
            client.estop()
            client.reset()


def _refused(call, status_code: int, code: str) -> StationError:
    with pytest.raises(StationError) as caught:
        call()
    assert caught.value.status_code == status_code and caught.value.code == code, caught.value
    return caught.value


def test_auto_jobs_and_refusals(station):
    jobs = {job["name"]: job for job in station.auto_jobs()}
    assert jobs["pick_sort"]["levels"] == [1, 2, 3] and jobs["pick_sort"]["judged"] is True
    _refused(lambda: station.auto("pick_sort", 1), 409, "not_calibrated")  # nothing calibrated yet
    assert "levels 1, 2, 3" in _refused(lambda: station.auto("pick_sort", 7), 422, "invalid").message
    _refused(lambda: station.auto("pick_sort", True), 422, "invalid")  # the client sends types as given
    assert "unknown job" in _refused(lambda: station.auto("juggle"), 422, "invalid").message
    _refused(lambda: station.auto_score(), 404, "not_found")
    assert station.status()["state"] == "idle"


def test_auto_with_wait_sorts_the_block_and_the_judge_gives_full_points(station):
    assert station.calibrate()["state"] == "succeeded"
    station.set_scene(objects=ONE_BLOCK)
    job = station.auto("pick_sort", level=1, wait=True)
    assert job["state"] == "succeeded" and job["detail"] == "pick_sort L1", job
    assert job["extra"]["task"]["done"] == 1 and job["extra"]["task"]["left"] == 0
    block = station.truth()["objects"][0]
    assert block["position_m"][0] > 0 and block["position_m"][1] < 0  # large blocks: y < 0, x > 0
    result = station.auto_score()
    assert result["job_id"] == job["id"] and result["final"] is True
    assert result["score"]["points"] == result["score"]["max_points"] == 40  # 30 for the block + 10 level bonus
    assert 0 < result["sim_time_s"] < 180


def test_auto_without_wait_returns_the_running_job_and_cancel_ends_it(station):
    station.set_scene(objects=ONE_BLOCK)
    job = station.auto("pick_sort", level=1)
    assert job["state"] == "running" and station.status()["state"] == "auto_sort"
    _refused(lambda: station.auto("pick_sort", 1), 409, "wrong_state")
    assert station.cancel_job()["id"] == job["id"]
    final = station.wait_job(60)
    assert final["id"] == job["id"] and final["state"] == "cancelled"
    assert station.truth()["gripper"]["holding_id"] is None
