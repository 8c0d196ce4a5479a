"""Operator grabs and drops check their path against the blocks and stacks the station knows (issue 21,
broken item 3): before, a grab on empty board 57 mm from a two-block stack came down with the fingers open
across the stack and knocked it over (base moved 32 mm, top block fell 38 mm). Now the open fingers' sweep is
checked against every detected block and stack (like the jobs' transfer checks), the fingers turned to pass
beside it, and a grab or drop whose path cannot clear one is refused naming it, nothing moved. Real HTTP on the
real-time RX200 simulation, calibrated from the board tags; ground truth from the simulation."""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import live
from armlab.scene import Scene
from armlab.workcell import load_workcell

TOKEN = "beside-stack-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
EDGE_M = load_workcell("rx200_armlab").block_edge_m("large")
STACK_XY = (0.10, 0.25)
GAP_M = 0.057  # the distance from the stack's centre to the clicked empty board
MOVED_TOL_M = 0.003

cell, url = live.module_fixtures(seed=21, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


def _stack() -> dict:
    return {"objects": [
        {"id": "base", "type": "block", "color": "red", "size": "large", "position_m": [*STACK_XY, EDGE_M / 2], "yaw_rad": 0.0},
        {"id": "top", "type": "block", "color": "blue", "size": "large", "position_m": [*STACK_XY, 1.5 * EDGE_M], "yaw_rad": 0.0},
    ]}


def _positions(cell) -> dict:
    return {o["id"]: np.asarray(o["position_m"], float) for o in cell.truth()["objects"]}


@pytest.fixture()
def calibrated(url, cell):
    cell.set_scene(Scene.from_dict(_stack()))
    with httpx.Client(base_url=url, timeout=120) as http:
        if http.get("/api/status").json()["state"] != "idle":
            http.post("/api/estop", headers=AUTH)
            http.post("/api/reset", headers=AUTH)
        assert http.post("/api/arm/home", params={"wait": "true"}, headers=AUTH).status_code == 200
        job = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH).json()["job"]
        assert job["state"] == "succeeded", job
        stack_top = 2 * EDGE_M
        live.wait_for(lambda: any(math.dist(d["position_m"][:2], STACK_XY) < 0.01 and abs(d["position_m"][2] - stack_top) < 0.008
                                  for d in http.get("/api/detections").json()["data"]), 20, 0.1)
        yield http


@pytest.mark.parametrize("direction_rad", [0.0, math.pi / 2], ids=["along x", "along y"])
def test_a_grab_on_empty_board_beside_a_stack_leaves_the_stack_standing(calibrated, cell, direction_rad):
    cell.set_scene(Scene.from_dict(_stack()))  # as the fixture left it (a previous case may have knocked it)
    before = _positions(cell)
    target = [STACK_XY[0] - GAP_M * math.cos(direction_rad), STACK_XY[1] - GAP_M * math.sin(direction_rad), 0.0]
    reply = calibrated.post("/api/grab", params={"wait": "true"}, json={"position_m": target}, headers=AUTH)
    assert reply.status_code == 200, reply.text  # planned beside the stack (the fingers turned across), not refused
    assert "closed on nothing" in reply.json()["job"]["message"], reply.json()["job"]  # it went down to the board and back
    after = _positions(cell)
    for name in ("base", "top"):
        moved = float(np.linalg.norm(after[name] - before[name]))
        assert moved < MOVED_TOL_M, f"the grab at {target} moved the stack's {name} block {moved * 1000:.1f} mm: {after[name]}"


def test_a_grab_boxed_in_by_two_stacks_is_refused_naming_one_and_nothing_moves(calibrated, cell):
    """Stacks 57 mm away along x and along y: the fingers fit neither way, so the grab is refused (422) with the
    block in the way named, before anything moves."""
    target = (STACK_XY[0] - GAP_M, STACK_XY[1])
    second = {"id": "side", "type": "block", "color": "green", "size": "large", "position_m": [target[0], target[1] - GAP_M, EDGE_M / 2],
              "yaw_rad": 0.0}
    second_top = {**second, "id": "side_top", "color": "yellow", "position_m": [target[0], target[1] - GAP_M, 1.5 * EDGE_M]}
    scene = _stack()
    scene["objects"] += [second, second_top]
    cell.set_scene(Scene.from_dict(scene))
    live.wait_for(lambda: sum(abs(d["position_m"][2] - 2 * EDGE_M) < 0.008 for d in calibrated.get("/api/detections").json()["data"]) == 2,
                  20, 0.1)
    before, q_before = _positions(cell), np.asarray(calibrated.get("/api/status").json()["joints_rad"])
    reply = calibrated.post("/api/grab", params={"wait": "true"}, json={"position_m": [*target, 0.0]}, headers=AUTH)
    assert reply.status_code == 422 and reply.json()["error"]["code"] == "unsafe", reply.text
    assert "block at" in reply.json()["error"]["message"], reply.text
    assert np.allclose(calibrated.get("/api/status").json()["joints_rad"], q_before, atol=2e-3)
    assert all(np.linalg.norm(_positions(cell)[k] - before[k]) < MOVED_TOL_M for k in before)
