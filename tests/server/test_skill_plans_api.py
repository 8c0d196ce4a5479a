"""Plan, then execute for click-grab and click-drop (issue 22 item 2) over real HTTP on the real-time simulation:
`?plan_only=true` on POST /api/grab or /api/drop answers the job's plan (its motions joined, its steps, the goal arm
where the gripper grasps or releases) and moves nothing (ground truth: joints, gripper, the block over sim time);
executing it runs the job on exactly those motions (the servos' reference holds the plan's goal while the gripper
acts) and picks / places the block (ground truth); a plan made before the scene changed is refused stale."""

from __future__ import annotations

import contextlib

import httpx
import numpy as np
import pytest

import live
from armlab.kinematics import load_arm
from armlab.scene import Scene
from armlab.station.config import StationConfig
from armlab.station.factory import make_sim_station
from armlab.workcell import load_workcell
from server.app import create_app

TOKEN = "skill-plans-token"
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
BLOCK_XY_M, DROP_XY_M = (0.0, 0.25), (0.15, 0.18)
EDGE_M = load_workcell("rx200_armlab").block_edge_m("large")
ARM = load_arm("rx200")


@pytest.fixture(scope="module")
def station_url(tmp_path_factory):
    built = {}

    def factory():
        built["sim"] = make_sim_station(StationConfig(workcell="rx200_armlab", sim={"time_scale": live.FAST_TIME_SCALE}),
                                        tmp_path_factory.mktemp("plans") / "db.sqlite3")
        return built["sim"]

    with live.serve(create_app(station_factory=factory, token=TOKEN)) as url:
        yield built["sim"].cell, url


def _block(cell) -> np.ndarray:
    return np.asarray(next(o for o in cell.truth()["objects"] if o["id"] == "b1")["position_m"], dtype=float)


def _truth(cell) -> tuple:
    return (np.asarray(cell.arm.read_joint_state().position_rad, float), cell.gripper.read_state().width_m, _block(cell))


def _still(cell, before, sim_s: float = 0.5) -> None:
    live.wait_sim(cell, sim_s)
    joints, width, block = _truth(cell)
    assert not cell.arm.is_moving() and np.abs(joints - before[0]).max() < 2e-3, "the arm moved"
    assert abs(width - before[1]) < 5e-4, "the gripper moved"
    assert np.linalg.norm(block - before[2]) < 1e-3, "the block moved"


def _plan(http, path: str, xyz) -> dict:
    answer = http.post(path, params={"plan_only": "true"}, json={"position_m": list(xyz)}, headers=AUTH)
    assert answer.status_code == 200, answer.text
    return answer.json()


def _execute(http, cell, plan: dict) -> tuple[dict, dict]:
    done, trace = live.execute_plan_recorded(http, cell, plan["plan_id"], AUTH)
    assert done.status_code == 200, done.text
    return done.json(), trace


def _held_reference_rad(trace: dict) -> np.ndarray:
    """The servos' reference where it rested longest between the job's motions (the gripper acting: no motion
    commanded). The rests before the first motion and after the last one are not between motions: how long they last
    depends on how soon the recording started and stopped (long on a loaded machine)."""
    reference = trace["reference_rad"]
    still = np.flatnonzero(np.abs(np.diff(reference, axis=0)).max(axis=1) < 1e-9)
    runs = [run for run in np.split(still, np.flatnonzero(np.diff(still) > 1) + 1)
            if len(run) and run[0] > 0 and run[-1] < len(reference) - 2]
    longest = max(runs, key=len)
    return reference[longest[0]]


def _one_block(xy_m, yaw_rad: float, color: str = "red") -> dict:
    return {"objects": [{"id": "b1", "type": "block", "color": color, "size": "large", "position_m": [*xy_m, EDGE_M / 2],
                         "yaw_rad": yaw_rad}]}


@contextlib.contextmanager
def _in_control(url: str):
    """A client holding the control lease (as the pad)."""
    with httpx.Client(base_url=url, timeout=120) as http:
        assert http.post("/api/control/take", headers=AUTH).status_code == 200
        yield http


def test_grab_and_drop_plan_without_moving_then_execute_exactly_that(station_url):
    cell, url = station_url
    cell.set_scene(Scene.from_dict(_one_block(BLOCK_XY_M, 0.0)))
    with _in_control(url) as http:
        assert http.post("/api/arm/home", params={"wait": "true"}, headers=AUTH).status_code == 200
        live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
        before = _truth(cell)
        plan = _plan(http, "/api/grab", (*BLOCK_XY_M, EDGE_M))
        assert plan["command"] == "grab" and plan["controller"] == "pad" and len(plan["steps"]) >= 3, plan
        assert np.allclose(plan["q_rad"][0], before[0], atol=0.02)
        grasp_at = ARM.fk(np.asarray(plan["goal_q_rad"]))[:3, 3]  # the goal arm: where the fingers close
        assert np.linalg.norm(grasp_at[:2] - np.asarray(BLOCK_XY_M)) < 0.005 and 0.0 < grasp_at[2] < EDGE_M, grasp_at
        assert http.get("/api/status").json()["state"] == "idle"
        _still(cell, before)

        done, trace = _execute(http, cell, plan)
        assert done["job"]["name"] == "grab" and done["job"]["state"] == "succeeded", done["job"]
        assert cell.truth()["gripper"]["holding_id"] == "b1"
        # the fingers closed with the servos held exactly at the plan's goal arm
        assert np.abs(_held_reference_rad(trace) - np.asarray(plan["goal_q_rad"])).max() < 1e-6
        again = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
        assert again.status_code == 409 and again.json()["error"]["reason"] == "executed", again.text

        live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
        carried = _truth(cell)
        drop = _plan(http, "/api/drop", (*DROP_XY_M, 0.0))
        assert drop["command"] == "drop", drop
        _still(cell, carried)
        assert cell.truth()["gripper"]["holding_id"] == "b1"
        done, trace = _execute(http, cell, drop)
        assert done["job"]["state"] == "succeeded", done["job"]
        live.wait_sim(cell, 0.5)
        block = _block(cell)
        assert cell.truth()["gripper"]["holding_id"] is None
        assert np.linalg.norm(block[:2] - np.asarray(DROP_XY_M)) < 0.008 and abs(block[2] - EDGE_M / 2) < 0.003, block
        assert np.abs(_held_reference_rad(trace) - np.asarray(drop["goal_q_rad"])).max() < 1e-6


def test_a_grab_plan_goes_stale_when_the_scene_changes_and_moves_nothing(station_url):
    cell, url = station_url
    cell.set_scene(Scene.from_dict(_one_block(BLOCK_XY_M, 0.3, "blue")))
    with _in_control(url) as http:
        live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
        plan = _plan(http, "/api/grab", (*BLOCK_XY_M, EDGE_M))
        assert http.post("/api/sim/scene", json=_one_block((0.1, 0.2), 0.3, "blue"), headers=AUTH).status_code == 200
        before = _truth(cell)
        stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
        assert stale.status_code == 409 and stale.json()["error"]["reason"] == "scene_changed", stale.text
        _still(cell, before)
        assert http.get("/api/jobs/current").json()["job"] is None or http.get("/api/status").json()["state"] == "idle"
