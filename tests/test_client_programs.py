"""armlab.client's teach, program and repeat calls against a real server on the real-time simulation."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "server"))
import live  # noqa: E402
from armlab.client import StationClient, StationError  # noqa: E402

TOKEN = "client-programs-token"

cell, url = live.module_fixtures(seed=4, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture()
def station(url):
    with StationClient(url, TOKEN) as client:
        yield client
        if client.status()["state"] != "idle":
            client.estop()
            client.reset()


def _repeat_extra(station) -> dict:
    job = station.current_job() or {}
    return (job.get("extra") or {}).get("repeat") or {}


def test_teach_edit_export_import_and_repeat_with_the_client(station):
    station.teach_start(discard_draft=True)
    station.move_joints([0.3, 0.0, 0.2, 0.5, 0.0], moving_time_s=0.6)
    assert station.teach_record(dwell_s=0.2)["count"] == 1
    station.move_joints([-0.3, 0.1, 0.1, 0.6, 0.0], moving_time_s=0.6)
    assert station.teach_record()["count"] == 2
    station.move_joints([0.0, 0.2, 0.0, 0.7, 0.0], moving_time_s=0.6)
    station.teach_record()
    assert station.teach_undo()["count"] == 2 and station.teach_draft()["count"] == 2
    program = station.teach_stop("client demo")
    renamed = station.update_program(program["id"], name="client demo 2")
    assert renamed["name"] == "client demo 2" and renamed["waypoints"] == program["waypoints"]
    copy = station.duplicate_program(program["id"], name="client copy")
    text = station.export_program(copy["id"], "csv")
    assert text.startswith("t_s,q1,q2,q3,q4,q5,gripper")
    imported = station.import_program(text, "csv", name="from the client")
    assert len(imported["waypoints"]) == 2 and imported["waypoints"][0]["dwell_s"] == pytest.approx(0.2)
    with pytest.raises(StationError) as caught:
        station.import_program("t_s,q1\n", "csv")
    assert caught.value.status_code == 422 and "line 1" in caught.value.message
    bag = station.export_program_file(copy["id"], "rosbag2")  # a ROS 2 bag (one MCAP file) and back
    assert bag.startswith(b"\x89MCAP0\r\n")
    from_bag = station.import_program_file(bag, "rosbag2", name="from a bag")
    assert [w["joints_rad"] for w in from_bag["waypoints"]] == [w["joints_rad"] for w in copy["waypoints"]]
    assert from_bag["samples"] == 3 and from_bag["waypoints"][0]["dwell_s"] == pytest.approx(0.2)  # 2 waypoints, one dwell row
    with pytest.raises(StationError) as caught:
        station.import_program_file(bag[:100], "rosbag2")
    assert caught.value.status_code == 422 and "ROS 2 bag" in caught.value.message
    station.delete_program(from_bag["id"])
    station.delete_program(copy["id"])
    assert copy["id"] not in [p["id"] for p in station.programs()]

    job = station.repeat(program["id"], cycles=None, speed_percent=70, wait=False)  # until stopped
    assert job["state"] == "running"
    live.wait_for(lambda: _repeat_extra(station).get("cycle", 0) >= 2, 120, 0.05)
    assert _repeat_extra(station)["cycles"] is None and _repeat_extra(station)["time_left_s"] is None
    assert station.set_job_speed(40)["extra"]["repeat"]["speed_percent"] in (40, 70)
    station.pause_job()
    live.wait_for(lambda: _repeat_extra(station).get("paused") and not station.status()["moving"], 30, 0.05)
    station.resume_job()
    trace = station.job_trace()
    assert trace["complete"] and trace["columns"][0] == "t_s" and len(trace["samples"]) > 10
    assert station.cancel_job()["state"] in ("running", "cancelled")
    final = station.wait_job(30)
    assert final["state"] == "cancelled" and station.status()["state"] == "idle"
    assert np.isfinite(station.status()["joints_rad"]).all()
