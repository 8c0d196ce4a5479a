"""Plan, then execute for a jog step (issue 22 item 2) over real HTTP on the real-time simulation: `?plan_only=true`
on POST /api/arm/step answers the step's plan (command jog, the gripper's path up 30 mm) and moves nothing (ground
truth: the joints over sim time); executing it moves the arm to the plan's goal (ground truth) along exactly that
trajectory; executing it again, or a plan made before the arm moved, is refused with nothing moved; a step the
gripper cannot make is refused when planned, and no plan is kept. The same for a repeat (`?plan_only=true` on its
start) and for the next step of a paused repeat (`POST /api/jobs/step?plan_only=true`: planned while the job waits,
nothing moves; executed, the servos are sent exactly the step shown and the arm stops at its goal, the job paused at the
step after; stale once the speed override changed, the arm was pushed away or the job's controls changed; refused while the job runs or without one)."""

from __future__ import annotations

import json

import httpx
import numpy as np
import pytest

import live
from armlab.kinematics import load_arm

TOKEN = "step-plans-token"
AUTH = {"Authorization": f"Bearer {TOKEN}", "X-Armlab-Controller": "pad"}
ARM = load_arm("rx200")
STEP_M = 0.03


cell, url = live.module_fixtures(seed=5, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture(scope="module")
def station_url(cell, url):
    """The simulation and a client holding the control lease (as the pad), the arm at home."""
    with httpx.Client(base_url=url, timeout=120) as http:
        assert http.post("/api/control/take", headers=AUTH).status_code == 200
        assert http.post("/api/arm/home", params={"wait": "true"}, headers=AUTH).status_code == 200
        yield cell, http


def _joints(cell) -> np.ndarray:
    return np.asarray(cell.arm.read_joint_state().position_rad, float)


def _at_rest(cell) -> np.ndarray:
    live.wait_for(lambda: not cell.arm.is_moving(), 15, 0.01)
    return _joints(cell)


def _still(cell, before: np.ndarray) -> None:
    live.wait_sim(cell, 0.5)
    assert not cell.arm.is_moving() and np.abs(_joints(cell) - before).max() < 2e-3, "the arm moved"


def _plan_step(http, axis: str = "z", distance_m: float = STEP_M):
    return http.post("/api/arm/step", params={"plan_only": "true"}, json={"axis": axis, "distance_m": distance_m},
                     headers=AUTH)


def test_a_step_planned_moves_nothing_and_executes_as_shown(station_url):
    cell, http = station_url
    before = _at_rest(cell)
    answer = _plan_step(http)
    assert answer.status_code == 200, answer.text
    plan = answer.json()
    assert plan["command"] == "jog" and plan["controller"] == "pad", plan
    start_m, goal_m = ARM.fk(before)[:3, 3], np.asarray(plan["gripper_path_m"][-1])
    assert goal_m[2] - start_m[2] == pytest.approx(STEP_M, abs=0.002) and np.linalg.norm(goal_m[:2] - start_m[:2]) < 0.002
    assert np.abs(np.asarray(plan["q_rad"][0]) - before).max() < 0.02
    assert http.get("/api/status").json()["state"] == "idle"
    _still(cell, before)

    done, trace = live.execute_plan_recorded(http, cell, plan["plan_id"], AUTH)
    assert done.status_code == 200, done.text
    after = _at_rest(cell)
    assert np.abs(after - np.asarray(plan["goal_q_rad"])).max() < 0.01, (after, plan["goal_q_rad"])
    assert ARM.fk(after)[2, 3] - start_m[2] == pytest.approx(STEP_M, abs=0.003)
    # the servos were sent the plan's trajectory: its reference ended exactly at the plan's goal
    assert np.abs(trace["reference_rad"][-1] - np.asarray(plan["goal_q_rad"])).max() < 1e-6

    again = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert again.status_code == 409 and again.json()["error"]["reason"] == "executed", again.text
    _still(cell, after)


def test_a_step_plan_made_before_the_arm_moved_is_refused_stale(station_url):
    cell, http = station_url
    _at_rest(cell)
    plan = _plan_step(http, "x", 0.02).json()
    assert http.post("/api/arm/step", params={"wait": "true"}, json={"axis": "x", "distance_m": -0.02},
                     headers=AUTH).status_code == 200
    before = _at_rest(cell)
    stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert stale.status_code == 409 and stale.json()["error"]["reason"] in ("arm_moved", "arm_commanded"), stale.text
    _still(cell, before)


def test_a_step_the_gripper_cannot_make_is_refused_when_planned(station_url):
    cell, http = station_url
    before = _at_rest(cell)
    refused = _plan_step(http, "z", -0.5)  # half a metre down: through the board
    assert refused.status_code == 422, refused.text
    _still(cell, before)
    listed = http.get("/api/status").json()
    assert listed["state"] == "idle"


WAYPOINTS_RAD = [[0.4, -0.2, 0.3, 0.6, 0.0], [0.0, 0.1, 0.2, 0.8, 0.3], [-0.4, -0.1, 0.2, 0.7, 0.0]]


def _distance_to_polyline(points: np.ndarray, q: np.ndarray) -> float:
    """The distance (joint space, rad) from q to the polyline through points (N, dof): the shown path is at most
    PLAN_SHOWN_SAMPLES samples of the plan, so a blended waypoint lies between two of them, wherever the grid falls."""
    a, b = points[:-1], points[1:]
    t = np.clip(np.einsum("ij,ij->i", q - a, b - a) / np.maximum(np.einsum("ij,ij->i", b - a, b - a), 1e-18), 0.0, 1.0)
    return float(np.linalg.norm(a + t[:, None] * (b - a) - q, axis=1).min())


def _program(http) -> int:
    content = json.dumps({"name": "plan-repeat", "waypoints": [{"joints_rad": q, "gripper": "release"} for q in WAYPOINTS_RAD]})
    answer = http.post("/api/programs/import", json={"format": "json", "content": content}, headers=AUTH)
    assert answer.status_code in (200, 201), answer.text
    return answer.json()["id"]


def test_a_repeat_planned_moves_nothing_then_runs_those_motions(station_url):
    cell, http = station_url
    program_id = _program(http)
    before = _at_rest(cell)
    answer = http.post(f"/api/programs/{program_id}/repeat", params={"plan_only": "true"}, json={"cycles": 1},
                       headers=AUTH)
    assert answer.status_code == 200, answer.text
    plan = answer.json()
    assert plan["command"] == "repeat" and plan["steps"][0].startswith("ease in") and plan["steps"][-1] == "home", plan
    assert np.abs(np.asarray(plan["q_rad"][0]) - before).max() < 0.02
    home = np.asarray(ARM.home_rad)
    assert np.abs(np.asarray(plan["goal_q_rad"]) - home).max() < 1e-6  # the way home shown at the end
    shown = np.asarray(plan["q_rad"])
    for q in WAYPOINTS_RAD:  # the path shown (the polyline through its samples, however decimated) passes every waypoint
        assert _distance_to_polyline(shown, np.asarray(q)) < 0.05, q
    assert http.get("/api/status").json()["state"] == "idle"
    _still(cell, before)

    done, trace = live.execute_plan_recorded(http, cell, plan["plan_id"], AUTH)
    assert done.status_code == 200, done.text
    assert done.json()["job"]["name"] == "repeat" and done.json()["job"]["state"] == "succeeded", done.text
    reference = trace["reference_rad"]  # what the simulated servos were sent, at every control tick
    for q in (WAYPOINTS_RAD[0], WAYPOINTS_RAD[-1]):  # the run stops at its first and last waypoints (blends between)
        assert np.abs(reference - np.asarray(q)).max(axis=1).min() < 1e-3, q
    # every point of the path shown was sent (within a control tick's travel): the motions run are the plan's
    misses = [np.abs(reference - q).max(axis=1).min() for q in shown]
    assert max(misses) < 5e-3, max(misses)
    assert np.abs(reference[-1] - home).max() < 1e-6
    again = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert again.status_code == 409 and again.json()["error"]["reason"] == "executed", again.text


def test_a_repeat_plan_made_before_the_arm_moved_is_refused_stale(station_url):
    cell, http = station_url
    program_id = _program(http)
    _at_rest(cell)
    plan = http.post(f"/api/programs/{program_id}/repeat", params={"plan_only": "true"}, json={"cycles": 2},
                     headers=AUTH).json()
    assert "one cycle shown" in plan["steps"][0], plan["steps"]
    assert http.post("/api/arm/step", params={"wait": "true"}, json={"axis": "z", "distance_m": 0.02},
                     headers=AUTH).status_code == 200
    before = _at_rest(cell)
    stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert stale.status_code == 409 and stale.json()["error"]["reason"] in ("arm_moved", "arm_commanded"), stale.text
    _still(cell, before)
    assert http.get("/api/status").json()["state"] == "idle"


# The next step of a paused repeat (single-stepping), planned, then executed -------------------------------------


def _repeat_status(http) -> dict:
    job = http.get("/api/jobs/current").json()["job"]
    return {"state": job["state"], **(job.get("extra") or {}).get("repeat", {})}


def _paused_at_rest(http, cell) -> dict:
    """The repeat waits paused (phase 'paused'), the arm at rest: its repeat progress."""
    live.wait_for(lambda: (r := _repeat_status(http)).get("phase") == "paused" and r["state"] == "running", 60, 0.05)
    _at_rest(cell)
    return _repeat_status(http)


def _plan_next_step(http):
    return http.post("/api/jobs/step", params={"plan_only": "true"}, headers=AUTH)


@pytest.fixture()
def paused_repeat(station_url):
    """A 1-cycle repeat of the 3-waypoint program, paused before its first motion (the ease-in)."""
    cell, http = station_url
    program_id = _program(http)
    _at_rest(cell)
    started = http.post(f"/api/programs/{program_id}/repeat", json={"cycles": 1}, headers=AUTH)
    assert started.status_code == 202, started.text
    assert http.post("/api/jobs/pause", headers=AUTH).status_code == 200
    _paused_at_rest(http, cell)
    yield cell, http
    http.post("/api/jobs/cancel", headers=AUTH)
    live.wait_for(lambda: http.get("/api/status").json()["state"] == "idle", 30, 0.05)


def _execute_step(http, cell, plan: dict) -> dict:
    """Execute a step's plan (?wait=true: until the job waits at its next step), check it ran exactly the plan's
    trajectory to the plan's goal (the servos' reference and the measured joints), and return the measured joints."""
    done, trace = live.execute_plan_recorded(http, cell, plan["plan_id"], AUTH)
    assert done.status_code == 200, done.text
    after = _at_rest(cell)
    goal = np.asarray(plan["goal_q_rad"])
    assert np.abs(after - goal).max() < 0.01, (after, goal)  # the measured arm at the planned goal
    reference = trace["reference_rad"]
    assert np.abs(reference[-1] - goal).max() < 1e-6  # what the servos were sent ended exactly there
    misses = [np.abs(reference - np.asarray(q)).max(axis=1).min() for q in plan["q_rad"]]
    assert max(misses) < 5e-3, max(misses)  # through every point of the path shown
    return after


def test_the_next_step_of_a_paused_repeat_is_planned_then_executed_as_shown(paused_repeat):
    cell, http = paused_repeat
    before = _joints(cell)
    answer = _plan_next_step(http)
    assert answer.status_code == 200, answer.text
    plan = answer.json()
    assert plan["command"] == "step" and plan["controller"] == "pad", plan
    assert plan["steps"] in (["move to waypoint 1"], ["move home"]), plan["steps"]  # the ease-in's first leg
    assert np.abs(np.asarray(plan["q_rad"][0]) - before).max() < 0.02
    _still(cell, before)  # planning moved nothing, and the job still waits
    assert _repeat_status(http)["paused"] is True

    _execute_step(http, cell, plan)
    progress = _paused_at_rest(http, cell)  # one step, then paused again
    # step on to waypoint 1 (the ease-in via home) and then to waypoint 2: each planned, then executed as shown
    for _ in range(3):
        plan = _plan_next_step(http).json()
        if plan["steps"] == ["move to waypoint 2"]:
            break
        _execute_step(http, cell, plan)
        progress = _paused_at_rest(http, cell)
    assert plan["steps"] == ["move to waypoint 2"], (plan, progress)
    assert np.abs(np.asarray(plan["goal_q_rad"]) - np.asarray(WAYPOINTS_RAD[1])).max() < 1e-6
    before = _joints(cell)
    _still(cell, before)
    _execute_step(http, cell, plan)
    assert np.abs(_joints(cell) - np.asarray(WAYPOINTS_RAD[1])).max() < 0.01
    assert _paused_at_rest(http, cell)["waypoint"] == 2


def test_a_next_step_plan_is_stale_once_the_speed_the_arm_or_the_job_changed(paused_repeat):
    cell, http = paused_repeat
    before = _joints(cell)
    plan = _plan_next_step(http).json()
    speed = http.get("/api/speed").json()["speed_percent"]
    assert http.patch("/api/jobs/current", json={"speed_percent": 40 if speed != 40 else 60}, headers=AUTH).status_code == 200
    stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert stale.status_code == 409 and stale.json()["error"]["reason"] == "speed_changed", stale.text
    _still(cell, before)

    # the arm pushed away while the job waits (the simulated servos' hold moved, as a hand would): stale, nothing sent
    plan = _plan_next_step(http).json()
    with cell.lock:
        held = np.asarray(cell.arm_reference(), float).copy()
        cell.apply_arm_reference(held + np.array([0.15, 0, 0, 0, 0]), np.zeros_like(held))  # 3x the start tolerance
    try:
        live.wait_for(lambda: abs(_joints(cell)[0] - held[0] - 0.15) < 0.01, 15, 0.01)
        stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
        assert stale.status_code == 409 and stale.json()["error"]["reason"] == "arm_moved", stale.text
        live.wait_sim(cell, 0.5)
        with cell.lock:  # nothing was sent: the servos still hold where the push left them
            assert np.abs(np.asarray(cell.arm_reference()) - held - [0.15, 0, 0, 0, 0]).max() < 1e-9
    finally:
        with cell.lock:
            cell.apply_arm_reference(held, np.zeros_like(held))
    live.wait_for(lambda: np.abs(_joints(cell) - held).max() < 0.005, 15, 0.01)
    _at_rest(cell)

    plan = _plan_next_step(http).json()
    assert http.post("/api/jobs/pause", headers=AUTH).status_code == 200  # the job's controls changed, nothing moved
    stale = http.post(f"/api/plans/{plan['plan_id']}/execute", headers=AUTH)
    assert stale.status_code == 409 and stale.json()["error"]["reason"] == "job_changed", stale.text
    live.wait_sim(cell, 0.5)
    with cell.lock:  # nothing was sent: the servos hold where they held
        assert np.abs(np.asarray(cell.arm_reference()) - held).max() < 1e-9
    assert _repeat_status(http)["paused"] is True


def test_the_next_step_is_planned_only_while_the_job_waits_paused(station_url):
    cell, http = station_url
    _at_rest(cell)
    refused = _plan_next_step(http)  # no job
    assert refused.status_code == 409, refused.text
    program_id = _program(http)
    started = http.post(f"/api/programs/{program_id}/repeat", json={"cycles": 1}, headers=AUTH)
    assert started.status_code == 202, started.text
    try:
        live.wait_for(lambda: cell.arm.is_moving(), 30, 0.01)
        refused = _plan_next_step(http)  # running: the arm moves
        assert refused.status_code == 409, refused.text
    finally:
        http.post("/api/jobs/cancel", headers=AUTH)
        live.wait_for(lambda: http.get("/api/status").json()["state"] == "idle", 30, 0.05)
