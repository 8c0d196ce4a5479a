"""The RX200 station tells clients its own arm: the websocket hello and GET /api/arm carry the RX200's five
joint names and limits (compared with config/arms/rx200.yaml read here) and its finger gripper; the
Interbotix facade refuses another robot_model than the station's arm. Real server, real websockets."""

from __future__ import annotations

import json
import math
from pathlib import Path

import httpx
import numpy as np
import pytest
import yaml
from websockets.sync.client import connect

import live
from armlab.client import InterbotixManipulatorXS, NotInterbotixArm

TOKEN = "hello-arm-token"
cell, url = live.module_fixtures(seed=3, token=TOKEN)


def _arm_file() -> dict:
    return yaml.safe_load((Path(__file__).resolve().parents[2] / "config/arms/rx200.yaml").read_text())


def test_hello_and_api_arm_carry_the_rx200_joints_and_fingers(url):
    arm_file = _arm_file()
    limits = [[math.radians(lo), math.radians(hi)] for lo, hi in zip(arm_file["limits"]["lower_deg"], arm_file["limits"]["upper_deg"])]
    with connect(url.replace("http://", "ws://") + f"/ws?token={TOKEN}", open_timeout=10) as ws:
        hello = json.loads(ws.recv(timeout=5))
    for arm in (hello["arm"], httpx.get(url + "/api/arm", timeout=10).json()):
        assert arm["name"] == "rx200" and arm["joint_names"] == arm_file["joint_names"] and len(arm["joint_names"]) == 5
        assert np.allclose(arm["joint_limits_rad"], limits)
        assert arm["gripper_type"] == "fingers" and arm["vendor"] == "interbotix" and arm["full_pose"] is False


def test_the_interbotix_facade_refuses_another_model_than_the_stations(url):
    with pytest.raises(NotInterbotixArm, match=r"rx200.*not the 'wx250'"):
        InterbotixManipulatorXS("wx250", "arm", "gripper", url=url, token=TOKEN)
