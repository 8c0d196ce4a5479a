"""armlab.client against a real server (uvicorn on a free port) on the real-time simulation."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent / "server"))
import live  # noqa: E402
from armlab.client import InterbotixManipulatorXS, StationClient, StationError, base_to_world  # noqa: E402

TOKEN = "client-token"


cell, url = live.module_fixtures(seed=2, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture()
def station(url):
    with StationClient(url, TOKEN) as client:
        yield client
        if client.status()["state"] != "idle":
            client.estop()
            client.reset()


def test_status_moves_and_errors(station):
    assert station.health()["status"] == "ok"
    status = station.move_joints([0.2, 0.0, 0.1, 0.0, 0.0], moving_time_s=0.6)
    assert np.allclose(status["joints_rad"], [0.2, 0.0, 0.1, 0.0, 0.0], atol=0.02)
    with pytest.raises(StationError) as caught:
        station.move_joints([0.0, 0.0, 0.0])
    assert caught.value.status_code == 422 and caught.value.code == "invalid"
    with pytest.raises(StationError) as caught:
        station.move_to([0.0, 1.0, 0.1])
    assert caught.value.code == "unreachable"
    station.estop()
    with pytest.raises(StationError) as caught:
        station.home()
    assert caught.value.status_code == 409 and caught.value.allowed == ["estop", "reset"]
    assert station.reset()["state"] == "idle"
    assert station.grasp()["gripper"]["command"] == "grasp"
    assert station.release()["gripper"]["command"] == "release"


def test_a_client_without_the_token_cannot_command(url):
    with StationClient(url, token="") as viewer:
        assert viewer.status()["state"] == "idle"
        with pytest.raises(StationError) as caught:
            viewer.home()
        assert caught.value.status_code == 401 and caught.value.code == "unauthorized"


def test_frames_iterator_acks_and_yields_newest_frames(station):
    frames = list(station.frames(view="color", layers=["grid"], max_frames=5))
    assert len(frames) == 5
    sequences = [frame.seq for frame in frames]
    assert sequences == sorted(set(sequences))
    assert frames[-1].decode().shape == (720, 1280, 3)
    assert all(0 <= frame.received_time_s - frame.capture_time_s < 2.0 for frame in frames)


def test_calibrate_detect_pixel_to_world_and_truth(station):
    station.set_scene(objects=[{"id": "y", "type": "block", "color": "yellow", "size": "large", "position_m": [0.1, 0.3, 0.019]}])
    job = station.calibrate()
    assert job["state"] == "succeeded", job
    assert station.calibration()["calibrated"]
    deadline = time.monotonic() + 10
    while not station.detections():
        assert time.monotonic() < deadline
        time.sleep(0.1)
    block = station.detections()[0]
    assert block["color"] == "yellow"
    point = station.pixel_to_world(*block["center_px"])
    assert np.allclose(point["position_m"], [0.1, 0.3, 0.038], atol=0.006)
    truth = station.truth()
    assert truth["objects"][0]["id"] == "y"
    assert len(station.frame_jpeg(view="depth")) > 1000


def test_interbotix_facade_runs_a_real_arm_script(url):
    bot = InterbotixManipulatorXS("rx200", "arm", "gripper", url=url, token=TOKEN, moving_time=0.8)
    try:
        bot.arm.go_to_home_pose()
        assert np.allclose(bot.arm.get_joint_commands(), 0.0, atol=0.02)
        goal, ok = bot.arm.set_ee_pose_components(x=0.25, y=0.05, z=0.12, pitch=1.0)
        assert ok
        pose = bot.arm.get_ee_pose()
        assert np.allclose(pose["position_m"], base_to_world(0.25, 0.05, 0.12), atol=0.004)
        assert pose["pitch_rad"] == pytest.approx(1.0, abs=0.02)
        q_before = bot.arm.get_joint_commands()
        _, ok = bot.arm.set_ee_pose_components(x=0.9, z=0.1)
        assert not ok
        assert np.allclose(bot.arm.get_joint_commands(), q_before, atol=0.003)
        bot.arm.set_joint_positions([0.3, 0.0, 0.0, 0.0, 0.0], moving_time=0.6)
        assert bot.arm.get_joint_commands()[0] == pytest.approx(0.3, abs=0.02)
        bot.gripper.grasp()
        bot.gripper.release()
        bot.arm.go_to_sleep_pose()
        sleep_q = [0.0, -1.80, 1.55, 0.8, 0.0]
        assert np.allclose(bot.arm.get_joint_commands(), sleep_q, atol=0.03)
    finally:
        bot.shutdown()
