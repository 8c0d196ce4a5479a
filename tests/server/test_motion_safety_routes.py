"""Issue 18 items 1 and 6 over real HTTP (real-time sim, real server): a joint move sent while the waist turns
continues its motion (command within the acceleration limit, no jump, measured on the simulation's clock at
every control tick), and poses onto the arm's base or into the board are a 422 naming why, nothing moving."""

from __future__ import annotations

import re

import httpx
import numpy as np
import pytest

import live
from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures

TOKEN = "motion-safety-token"
HEADERS = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "script"}
ACCEL = np.asarray(load_arm("rx200").accel_limit_rad_s2, dtype=float)

cell, url = live.module_fixtures(seed=5, token=TOKEN)


def _sim_wait(cell, duration_s: float) -> None:
    start = cell.sim_time_s
    live.wait_for(lambda: cell.sim_time_s >= start + duration_s, 30, 0.002)


def test_a_joint_move_sent_while_the_waist_turns_continues_its_motion(url, cell):
    with httpx.Client(base_url=url, headers=HEADERS, timeout=30) as http:
        assert http.post("/api/arm/joints", json={"q_rad": [-2.6, 0, 0, 0, 0]}, params={"wait": "true"}).status_code in (200, 202)
        live.wait_for(lambda: not cell.arm.is_moving(), 10, 0.01)
        cell.start_joint_recording()
        assert http.post("/api/arm/joints", json={"q_rad": [2.6, 0, 0, 0, 0]}).status_code in (200, 202)
        live.wait_for(lambda: cell.arm.read_joint_state().velocity_rad_s[0] > 2.5, 10, 0.002)  # turning at ~3 rad/s (for 1 s)
        reply = http.post("/api/arm/joints", json={"q_rad": [-1.0, 0, 0, 0, 0]})  # reverse
        assert reply.status_code in (200, 202), reply.text
        live.wait_for(lambda: not cell.arm.is_moving(), 20, 0.01)
        _sim_wait(cell, 0.1)
    figures = motion_figures(cell.stop_joint_recording())
    # The command within the limit (a lone trapezoid reads 1.002x in this 20 ms measure), no jump, on the simulation's
    # clock, also on a CPU-starved machine: the arm takes the takeover's start from the station (start_time_s), so a
    # send held up by a physics batch continues the same curve (before: 9-11x under load, 1 run in 4 with 3 CPU hogs).
    command, measured = figures.ratio(ACCEL)
    assert command <= 1.01 and figures.step_rad.max() < 1e-3, (command, figures.step_rad.max())
    assert measured <= 1.5, measured
    assert abs(cell.arm.read_joint_state().position_rad[0] + 1.0) < 0.02


@pytest.mark.parametrize("position_m, reason", [([0.0, 0.0, 0.0], "board|own base"), ([0.25, 0.0, 0.0], "fingers would go")])
def test_a_pose_onto_the_base_or_into_the_board_is_refused(url, cell, position_m, reason):
    with httpx.Client(base_url=url, headers=HEADERS, timeout=30) as http:
        http.post("/api/arm/home", params={"wait": "true"})
        live.wait_for(lambda: not cell.arm.is_moving(), 10, 0.01)
        before = cell.arm.read_joint_state().position_rad
        reply = http.post("/api/arm/pose", json={"position_m": position_m})
        assert reply.status_code == 422 and reply.json()["error"]["code"] == "unsafe", reply.text
        assert re.search(reason, reply.json()["error"]["message"]), reply.text
        _sim_wait(cell, 0.3)
        assert np.max(np.abs(cell.arm.read_joint_state().position_rad - before)) < 5e-3
