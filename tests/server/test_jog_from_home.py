"""Cartesian jog from Home (issue 21, broken item 4): on the RX200 an X step from Home was always refused
("yaw would change by 3.50° … wrist_rotate jumps 1.571 rad (IK changed branch)": the gripper is level there,
the wrist roll cannot hold its heading, and asking IK to hold it flipped the wrist); on the UR3 every step
from Home was refused (Home was the upright pose, the arm stretched to its full reach: a singularity).
Now X+/X−/Y+/Y−/Z+/Z− steps of 25 mm from Home move the tool point 25 mm along the axis on both arms, over
real HTTP on the real-time simulation, measured by FK of the simulated arm's joints: the RX200 keeps its pitch
and wrist roll and its yaw turns with the waist (a 5-joint arm can do nothing else level), the UR3 keeps
the tool's whole orientation."""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import live
from armlab.station.config import StationConfig
from armlab.station.factory import make_sim_station
from armlab.workcell import load_workcell_arm
from server.app import create_app

TOKEN = "jog-home-token"
PAGE = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
STEP_M = 0.025  # the page's 25 mm step (the issue's 3.50° of yaw at the RX200's 409 mm radius)
POSITION_TOL_M = 0.002  # the measured tool point (servo tracking included)
ANGLE_TOL_RAD = math.radians(0.6)
STEPS = [(axis, sign) for axis in "xyz" for sign in (1, -1)]


@pytest.fixture(scope="module", params=["rx200_armlab", "ur3_suction"])
def station_url(request, tmp_path_factory):
    built = {}

    def factory():
        built["sim"] = make_sim_station(StationConfig(workcell=request.param, sim={"time_scale": live.FAST_TIME_SCALE}),
                                        tmp_path_factory.mktemp("jog") / "db.sqlite3")
        return built["sim"]

    with live.serve(create_app(station_factory=factory, token=TOKEN)) as url:
        yield request.param, built["sim"], url


def _measured(sim, model) -> tuple[np.ndarray, np.ndarray]:
    q = np.asarray(sim.cell.arm.read_joint_state().position_rad, float)
    return model.fk(q), q


def _yaw(T) -> float:
    return math.atan2(T[1, 1], T[0, 1])


@pytest.mark.parametrize("axis, sign", STEPS)
def test_a_25_mm_step_from_home_moves_along_its_axis(station_url, axis, sign):
    workcell, sim, url = station_url
    model = load_workcell_arm(workcell)
    with httpx.Client(base_url=url, timeout=30, headers=PAGE) as http:
        assert http.post("/api/arm/home", params={"wait": "true"}).status_code == 200
        live.wait_for(lambda: not http.get("/api/status").json()["moving"], 10)
        T0, q0 = _measured(sim, model)
        reply = http.post("/api/arm/step", json={"axis": axis, "distance_m": sign * STEP_M}, params={"wait": "true"})
        assert reply.status_code == 200, reply.text
        live.wait_for(lambda: not http.get("/api/status").json()["moving"], 10)
        T1, q1 = _measured(sim, model)
    moved = T1[:3, 3] - T0[:3, 3]
    expected = np.zeros(3)
    expected["xyz".index(axis)] = sign * STEP_M
    assert np.abs(moved - expected).max() < POSITION_TOL_M, f"{workcell} {axis}{sign:+}: moved {moved * 1000} mm"
    if model.dof == 5:  # pitch (approach axis' tilt) and wrist roll kept; the yaw turns with the waist
        assert abs(T1[2, 0] - T0[2, 0]) < math.sin(ANGLE_TOL_RAD)
        assert abs(q1[4] - q0[4]) < ANGLE_TOL_RAD, "wrist_rotate turned"
        assert abs(math.remainder(_yaw(T1) - _yaw(T0) - (q1[0] - q0[0]), 2 * math.pi)) < ANGLE_TOL_RAD
    else:  # the whole orientation kept
        turned = math.acos(np.clip((np.trace(T0[:3, :3].T @ T1[:3, :3]) - 1) / 2, -1, 1))
        assert turned < ANGLE_TOL_RAD, f"{workcell}: the tool turned {math.degrees(turned):.2f}°"
