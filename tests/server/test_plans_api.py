"""Plan, then execute (issue 22 item 2) over real HTTP on the real-time simulation: `?plan_only=true` on a pose or
joint move answers the plan (id, trajectory, gripper path, goal) and moves nothing (ground truth: the simulated
joints and gripper point over sim time); POST /api/plans/{id}/execute then runs exactly that trajectory (the servos'
reference recorded at every control tick equals the plan) to the goal; an unknown, discarded, executed or stale
plan, another controller's plan, or no token is refused with a clear error and nothing moves; a plan into the
board is refused naming the part."""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import live
from armlab.kinematics import load_arm

TOKEN = "plans-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
PAD = {**AUTH, "X-Armlab-Controller": "pad"}
OTHER = {**AUTH, "X-Armlab-Controller": "other"}
START_RAD = [0.3, 0.0, 0.3, 0.9, 0.0]
ARM = load_arm("rx200")
GRIPPER_GEOMS = {"fingers": {"left_finger_link", "right_finger_link", "left_pad", "right_pad"}, "palm": {"palm"}}

cell, url = live.module_fixtures(seed=29, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture()
def http(url, cell):
    """The pad controls the idle station, the arm at rest at START_RAD."""
    with httpx.Client(base_url=url, timeout=60) as client:
        client.post("/api/control/take", headers=PAD)
        client.put("/api/speed", json={"speed_percent": 100.0}, headers=PAD)
        moved = client.post("/api/arm/joints", json={"q_rad": START_RAD, "moving_time_s": 1.0}, params={"wait": "true"}, headers=PAD)
        assert moved.status_code == 200, moved.text
        live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
        yield client


def _truth(cell) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(cell.arm.read_joint_state().position_rad, dtype=float), cell.gripper_point_m()


def _still(cell, before, sim_s: float = 0.3) -> None:
    """Over sim_s of simulated time the arm was not commanded: it does not move, joints and gripper point unchanged."""
    live.wait_sim(cell, sim_s)
    joints, point = _truth(cell)
    assert not cell.arm.is_moving(), "the arm was commanded"
    assert np.abs(joints - before[0]).max() < 2e-3, f"the joints moved: {joints - before[0]}"
    assert np.linalg.norm(point - before[1]) < 0.002, f"the gripper point moved {np.linalg.norm(point - before[1]) * 1000:.1f} mm"


def _error(response, status_code: int, code: str) -> dict:
    assert response.status_code == status_code, response.text
    body = response.json()["error"]
    assert body["code"] == code, body
    return body


def _plan(http, path: str, body: dict, headers=PAD) -> dict:
    answer = http.post(path, json=body, params={"plan_only": "true"}, headers=headers)
    assert answer.status_code == 200, answer.text
    plan = answer.json()
    assert plan["plan_id"] and len(plan["times_s"]) == len(plan["q_rad"]) == len(plan["gripper_path_m"]) >= 2, plan
    return plan


def _start_offset_s(trace: dict, plan: dict) -> float:
    """The clock time of the plan's t = 0 in the recorded reference (its first tick away from the start)."""
    reference, start = trace["reference_rad"], np.asarray(plan["q_rad"][0])
    moving = np.flatnonzero(np.abs(reference - start).max(axis=1) > 1e-7)
    assert moving.size, "the reference never left the plan's start"
    first = int(moving[0])
    return float(trace["time_s"][first - 1]) if first > 0 else float(trace["time_s"][0])


def _max_gap_from_plan_rad(trace: dict, plan: dict) -> float:
    """The largest difference between the recorded servo reference and the plan (interpolated at the same times),
    with the plan's start fitted to the recording within ±20 ms."""
    times, q = np.asarray(plan["times_s"]), np.asarray(plan["q_rad"])
    t_rec, reference = trace["time_s"], trace["reference_rad"]
    guess = _start_offset_s(trace, plan)
    best = math.inf
    for t0 in np.arange(guess - 0.02, guess + 0.02, 0.0005):
        t = t_rec - t0
        inside = (t >= 0.0) & (t <= times[-1])
        planned = np.stack([np.interp(t[inside], times, q[:, j]) for j in range(q.shape[1])], axis=1)
        best = min(best, float(np.abs(planned - reference[inside]).max()))
    return best


def _execute_recorded(http, cell, plan: dict) -> dict:
    """Execute the plan (waiting for the arm) with the servos' reference recorded at every tick: the trace."""
    done, trace = live.execute_plan_recorded(http, cell, plan["plan_id"], PAD)
    assert done.status_code == 200, done.text
    return trace


def test_plan_only_moves_nothing_and_execute_runs_exactly_the_plan(http, cell):
    target = [0.22, -0.08, 0.12]
    before = _truth(cell)
    plan = _plan(http, "/api/arm/pose", {"position_m": target, "pitch_rad": math.pi / 2, "moving_time_s": 2.5})
    assert plan["command"] == "move_to" and plan["controller"] == "pad"
    assert plan["duration_s"] >= 2.5 and plan["times_s"][-1] == pytest.approx(plan["duration_s"])
    assert np.allclose(plan["q_rad"][0], before[0], atol=0.02) and np.allclose(plan["q_rad"][-1], plan["goal_q_rad"])
    assert np.allclose(plan["gripper_path_m"][-1], target, atol=1e-3) and np.allclose(plan["gripper_pose"]["position_m"], target, atol=1e-3)
    assert np.allclose(plan["gripper_path_m"][0], ARM.fk(np.asarray(plan["q_rad"][0]))[:3, 3], atol=1e-6)
    assert http.get("/api/status").json()["state"] == "idle"
    _still(cell, before, sim_s=0.5)

    trace = _execute_recorded(http, cell, plan)
    live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
    joints, point = _truth(cell)
    assert np.abs(joints - np.asarray(plan["goal_q_rad"])).max() < 0.02, joints
    assert np.linalg.norm(point - np.asarray(target)) < 0.006, point
    # The servos were fed exactly the plan: its (decimated) samples, interpolated, within the interpolation's error.
    assert _max_gap_from_plan_rad(trace, plan) < 2e-3
    again = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=PAD)
    assert _error(again, 409, "stale_plan")["reason"] == "executed"


def test_a_joint_plan_executes_at_its_own_duration(http, cell):
    """A joint plan with a long moving time: executing it runs that duration (a re-plan at the default would not)."""
    goal = [-0.2, 0.1, 0.2, 0.6, 0.3]
    plan = _plan(http, "/api/arm/joints", {"q_rad": goal, "moving_time_s": 3.0})
    assert plan["command"] == "move_joints" and plan["duration_s"] >= 3.0
    trace = _execute_recorded(http, cell, plan)
    assert _max_gap_from_plan_rad(trace, plan) < 2e-3
    assert np.abs(_truth(cell)[0] - np.asarray(goal)).max() < 0.02


@pytest.mark.parametrize("pose", ["home", "sleep"])
def test_home_and_sleep_plan_without_moving_then_execute(http, cell, pose):
    """The named poses plan as the buttons would move (the arm's own home and sleep joints) and move nothing."""
    goal = np.asarray(ARM.home_rad if pose == "home" else ARM.sleep_rad, dtype=float)
    before = _truth(cell)
    plan = _plan(http, f"/api/arm/{pose}", {"moving_time_s": 2.0})
    assert plan["command"] == pose and np.allclose(plan["goal_q_rad"], goal) and plan["duration_s"] >= 2.0
    _still(cell, before, sim_s=0.4)
    trace = _execute_recorded(http, cell, plan)
    assert _max_gap_from_plan_rad(trace, plan) < 2e-3
    live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
    assert np.abs(_truth(cell)[0] - goal).max() < 0.02


def test_bad_plan_ids_and_callers_are_refused_and_nothing_moves(http, cell):
    plan = _plan(http, "/api/arm/joints", {"q_rad": [0.0, 0.1, 0.2, 0.7, 0.0]})
    execute = f"/api/plans/{plan['plan_id']}/execute"
    before = _truth(cell)

    assert "no plan" in _error(http.post("/api/plans/plan-000000000000/execute", headers=PAD), 404, "not_found")["message"]
    _error(http.post(execute), 401, "unauthorized")  # no token
    _error(http.post(execute, headers={"Authorization": "Bearer wrong"}), 401, "unauthorized")
    # another controller, while the pad holds the lease, and after taking it over
    assert "pad" in _error(http.post(execute, headers=OTHER), 409, "not_controller")["message"]
    assert http.post("/api/control/take", headers=OTHER).status_code == 200
    assert "made by 'pad'" in _error(http.post(execute, headers=OTHER), 409, "not_controller")["message"]
    # its maker without the lease: refused as any command is
    assert "'other'" in _error(http.post(execute, headers=PAD), 409, "not_controller")["message"]
    _still(cell, before)
    assert http.post("/api/control/take", headers=PAD).status_code == 200

    # discarded: gone
    assert http.delete(f"/api/plans/{plan['plan_id']}", headers=OTHER).status_code == 409
    discarded = http.delete(f"/api/plans/{plan['plan_id']}", headers=PAD)
    assert discarded.status_code == 200 and discarded.json()["discarded"] is True, discarded.text
    _error(http.post(execute, headers=PAD), 404, "not_found")
    _error(http.delete(f"/api/plans/{plan['plan_id']}", headers=PAD), 404, "not_found")
    _error(http.post("/api/plans/not%20an%20id/execute", headers=PAD), 422, "invalid")
    _still(cell, before)

    # e-stopped: refused by the gate's state check, nothing moves; after the reset the arm was halted: stale
    fresh = _plan(http, "/api/arm/joints", {"q_rad": [0.0, 0.1, 0.2, 0.7, 0.0]})
    assert http.post("/api/estop", headers=PAD).status_code == 200
    _error(http.post(f"/api/plans/{fresh['plan_id']}/execute", headers=PAD), 409, "wrong_state")
    assert http.post("/api/reset", headers=PAD).status_code == 200
    assert _error(http.post(f"/api/plans/{fresh['plan_id']}/execute", headers=PAD), 409, "stale_plan")["reason"] == "halted"
    _still(cell, before)


def test_a_plan_goes_stale_when_the_arm_the_speed_or_the_scene_changed(http, cell):
    plan = _plan(http, "/api/arm/joints", {"q_rad": [0.5, 0.0, 0.2, 0.8, 0.0]})
    moved = http.post("/api/arm/joints", json={"q_rad": [0.1, 0.0, 0.3, 0.9, 0.0]}, params={"wait": "true"}, headers=PAD)
    assert moved.status_code == 200
    before = _truth(cell)
    stale = _error(http.post(f"/api/plans/{plan['plan_id']}/execute", headers=PAD), 409, "stale_plan")
    assert stale["reason"] == "arm_moved" and "moved" in stale["message"], stale
    _still(cell, before)

    # commanded away and back to where the plan starts: still stale (another motion ran since)
    plan = _plan(http, "/api/arm/joints", {"q_rad": [0.5, 0.0, 0.2, 0.8, 0.0]})
    for q in ([0.2, 0.0, 0.3, 0.9, 0.0], [0.1, 0.0, 0.3, 0.9, 0.0]):
        assert http.post("/api/arm/joints", json={"q_rad": q}, params={"wait": "true"}, headers=PAD).status_code == 200
    live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
    before = _truth(cell)
    stale = _error(http.post(f"/api/plans/{plan['plan_id']}/execute", headers=PAD), 409, "stale_plan")
    assert stale["reason"] == "arm_commanded", stale
    _still(cell, before)

    # the speed override changed: the plan was paced at the old one
    plan = _plan(http, "/api/arm/joints", {"q_rad": [0.5, 0.0, 0.2, 0.8, 0.0]})
    assert http.put("/api/speed", json={"speed_percent": 50.0}, headers=PAD).status_code == 200
    stale = _error(http.post(f"/api/plans/{plan['plan_id']}/execute", headers=PAD), 409, "stale_plan")
    assert stale["reason"] == "speed_changed" and "50 %" in stale["message"], stale
    _still(cell, before)
    assert http.put("/api/speed", json={"speed_percent": 100.0}, headers=PAD).status_code == 200

    # a new scene
    plan = _plan(http, "/api/arm/joints", {"q_rad": [0.5, 0.0, 0.2, 0.8, 0.0]})
    assert http.post("/api/sim/scene", json={"objects": []}, headers=PAD).status_code == 200
    stale = _error(http.post(f"/api/plans/{plan['plan_id']}/execute", headers=PAD), 409, "stale_plan")
    assert stale["reason"] == "scene_changed" and "scene" in stale["message"], stale
    _still(cell, before)


def test_a_plan_while_the_arm_moves_is_refused(http, cell):
    assert http.post("/api/arm/joints", json={"q_rad": [0.6, 0.0, 0.3, 0.9, 0.0], "moving_time_s": 3.0}, headers=PAD).status_code == 200
    busy = http.post("/api/arm/joints", json={"q_rad": START_RAD}, params={"plan_only": "true"}, headers=PAD)
    assert "at rest" in _error(busy, 409, "wrong_state")["message"]
    live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)


def test_a_plan_into_the_board_is_refused_naming_the_part(http, cell):
    before = _truth(cell)
    low = ARM.ik([0.25, 0.0, 0.004], pitch=math.pi / 2)  # the gripper point 4 mm above the board: the fingers go in
    refused = http.post("/api/arm/joints", json={"q_rad": [float(v) for v in low]}, params={"plan_only": "true"}, headers=PAD)
    body = _error(refused, 422, "unsafe")
    assert "board" in body["message"] and body["part"] in ("fingers", "palm"), body
    # Where it happens, to draw: the simulation's truth puts that part of the gripper into the board at at_q_rad,
    # and the 3-D scene names the part's links, links of the arm's URDF.
    assert len(body["at_q_rad"]) == 5 and cell.contact_depth_at_mm(body["at_q_rad"], GRIPPER_GEOMS[body["part"]]) > 0.5, body
    scene = http.get("/api/view3d/scene").json()["arm"]
    links = scene["part_links"][body["part"]]
    assert links and all(f'<link name="{link}">' in scene["urdf"] for link in links), links
    assert set(links) <= {"left_finger_link", "right_finger_link", "wrist_rotate_link"}, links
    below = http.post("/api/arm/pose", json={"position_m": [0.25, 0.0, -0.05]}, params={"plan_only": "true"}, headers=PAD)
    assert "below the table" in _error(below, 422, "unreachable")["message"]
    limit = http.post("/api/arm/joints", json={"q_rad": [0.0, 3.0, 0.0, 0.0, 0.0]}, params={"plan_only": "true"}, headers=PAD)
    assert "shoulder" in _error(limit, 422, "invalid")["message"]
    _still(cell, before)
