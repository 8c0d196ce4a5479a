"""Plan, then execute from the page (issue 22 item 2): a typed target's Plan asks the station for the plan without
moving (?plan_only=true), draws the see-through goal arm and the gripper's path in the 3-D panel, and waits; the arm
does not move (ground truth over sim time); Execute runs that plan to the goal (ground truth); Discard drops it
(the station no longer has it); a plan into the board is refused with the station's reason in place, the arm drawn
where it would fail with the offending part's links in red, and a plan gone stale because the arm moved is refused at
Execute with its reason. With "preview before moving" on, click-grab, a jog step and a paused repeat's Step plan first
and wait for Execute. Real server, real Chromium."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from browser_helpers import canvas_point, enter_click_mode, page_with_the_arm_at, ready_idle

pytestmark = pytest.mark.browser

START_RAD = [0.3, 0.0, 0.3, 0.9, 0.0]
TARGET_MM = (230.0, 60.0, 90.0)


@pytest.fixture
def page(browser, server):
    page = page_with_the_arm_at(browser, server, START_RAD, "!document.getElementById('btn-target-plan').disabled")
    yield page
    page.close()


def _truth(server) -> tuple[np.ndarray, np.ndarray, float]:
    t = server.get("/api/sim/truth")
    return np.asarray(t["arm"]["position_rad"]), np.asarray(t["gripper"]["position_m"]), float(t["time_s"])


def _after_sim_time(server, sim_time_s: float, timeout_s: float = 30.0):
    """The truth once the simulation's clock has passed sim_time_s (a condition, not a sleep)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        truth = _truth(server)
        if truth[2] >= sim_time_s:
            return truth
        time.sleep(0.05)
    raise AssertionError(f"the simulation did not reach t = {sim_time_s:.2f} s")


def _result(page, state: str) -> str:
    try:
        page.wait_for_function(f"document.getElementById('target-result').dataset.state === '{state}'", timeout=30_000)
    except Exception as error:  # noqa: BLE001 - say what the page shows instead
        shown = page.evaluate("[document.getElementById('target-result').dataset.state, "
                              "document.getElementById('target-result').textContent]")
        raise AssertionError(f"the result never read {state!r}; it reads {shown}; page errors {page.errors}") from error
    return page.text_content("#target-result")


def _plan_pose(page, x, y, z, pitch="90"):
    for field, value in (("x", x), ("y", y), ("z", z), ("pitch", pitch), ("yaw", "")):
        page.fill(f"#target-{field}", str(value))
    page.click("#btn-target-plan")


def _shown_plan(page) -> dict:
    """The plan the 3-D panel draws once it has loaded: its id, the goal arm's joints, the path's point count."""
    page.wait_for_function("window.armlab?.view3d?.planShown && armlab.view3d.planShown.goal.loaded", timeout=60_000)
    return page.evaluate("""(() => { const p = armlab.view3d.planShown;
        const names = armlab.view3d.armDescription.joint_names;
        return { id: p.id, joints: names.map((n) => p.goal.robot.joints[n].angle),
                 points: p.path.geometry.attributes.position.count }; })()""")


def test_the_buttons_stay_put_when_the_focus_leaves_a_field(page):
    """The key hint under the jog changes its text with the focus; it grew a line when a field lost the focus and
    moved the Plan and Go buttons 13 px between a click's press and release (the click went to their row)."""
    page.locator("#btn-target-plan").scroll_into_view_if_needed()
    page.focus("#target-yaw")
    focused = page.evaluate("document.getElementById('btn-target-plan').getBoundingClientRect().y")
    page.evaluate("document.activeElement.blur()")
    page.wait_for_function("document.getElementById('jog-keys').dataset.keys === 'jog'")
    assert page.evaluate("document.getElementById('btn-target-plan').getBoundingClientRect().y") == focused


def test_plan_shows_the_goal_arm_and_moves_nothing_then_execute_reaches_it(page, server):
    q0, point0, t0 = _truth(server)
    _plan_pose(page, *TARGET_MM)
    assert "nothing moves until Execute" in _result(page, "planned")
    shown = _shown_plan(page)
    plan_id = shown["id"]
    q1, point1, t1 = _after_sim_time(server, t0 + 1.0)
    assert t1 > t0 and np.abs(q1 - q0).max() < 2e-3 and np.linalg.norm(point1 - point0) < 0.002, "the arm moved on Plan"
    goal_q = np.asarray(shown["joints"])
    assert shown["points"] >= 2
    page.click("#btn-plan-execute")
    assert "executing the plan" in _result(page, "sent")
    server.wait_status(lambda s: not s["moving"] and s["state"] == "idle", 30.0, "the arm to arrive")
    q2, point2, _ = _truth(server)
    assert np.linalg.norm(point2 - np.asarray(TARGET_MM) / 1000.0) < 0.006, point2
    assert np.abs(q2 - goal_q).max() < 0.02, (q2, goal_q)  # the goal arm drawn was where the arm went
    assert page.evaluate("armlab.view3d.planShown") is None
    again = server.request("POST", f"/api/plans/{plan_id}/execute")
    assert again.status_code == 409 and again.json()["error"]["reason"] == "executed"
    assert page.errors == []


def test_discard_drops_the_plan_and_a_stale_plan_is_refused_at_execute(page, server):
    _plan_pose(page, *TARGET_MM)
    plan_id = _shown_plan(page)["id"]
    page.click("#btn-plan-discard")
    assert "discarded" in _result(page, "sent")
    assert page.is_hidden("#plan-box") and page.evaluate("armlab.view3d.planShown") is None
    assert server.request("POST", f"/api/plans/{plan_id}/execute").status_code == 404

    _plan_pose(page, *TARGET_MM)
    _shown_plan(page)
    server.post("/api/arm/joints?wait=true", {"q_rad": [0.0, 0.0, 0.3, 0.9, 0.0], "moving_time_s": 1.0})
    ready_idle(server)
    q_before, _, _ = _truth(server)
    page.click("#btn-plan-execute")
    text = _result(page, "refused")
    assert "stale" in text and "moved" in text, text
    ready_idle(server)
    assert np.abs(_truth(server)[0] - q_before).max() < 2e-3  # nothing moved


def test_a_plan_into_the_board_is_refused_with_the_reason_and_nothing_moves(page, server):
    q0, _, _ = _truth(server)
    _plan_pose(page, 250, 0, -40)
    text = _result(page, "refused")
    assert "no plan" in text and ("below the table" in text or "board" in text), text
    assert page.is_hidden("#plan-box")
    assert np.abs(_truth(server)[0] - q0).max() < 2e-3


RED_LINKS_JS = """(() => { const r = armlab.view3d?.refusalShown; if (!r || !r.figure.loaded) return null;
    const rgb = (mesh) => [mesh.material.color.r, mesh.material.color.g, mesh.material.color.b, mesh.material.opacity];
    const names = armlab.view3d.armDescription.joint_names;
    return { part: r.part, links: r.links, joints: names.map((n) => r.figure.robot.joints[n].angle),
             offending: r.links.flatMap((l) => r.figure.linkMeshes(l).map(rgb)),
             others: Object.keys(r.figure.robot.links).filter((l) => !r.links.includes(l))
                       .flatMap((l) => r.figure.linkMeshes(l).map(rgb)) }; })()"""


def test_a_plan_into_the_board_draws_the_offending_part_in_red_and_moves_nothing(page, server):
    """Fingers 4 mm above the board: the IK reaches it, the body check refuses it; the page draws the arm at the
    joints the station names (the same answer over REST) with the part's links red, the rest see-through grey."""
    q0, _, _ = _truth(server)
    _plan_pose(page, 250, 0, 4)
    text = _result(page, "refused")
    assert "board" in text and "in red in the 3-D view" in text, text
    page.wait_for_function(f"({RED_LINKS_JS}) !== null", timeout=60_000)
    shown = page.evaluate(RED_LINKS_JS)
    answer = server.request("POST", "/api/arm/pose?plan_only=true", json={"position_m": [0.25, 0.0, 0.004], "pitch_rad": 1.5707963})
    error = answer.json()["error"]
    assert answer.status_code == 422 and error["part"] == shown["part"] in ("fingers", "palm"), error
    assert np.abs(np.asarray(shown["joints"]) - np.asarray(error["at_q_rad"])).max() < 1e-6
    red = lambda r, g, b: r > 0.5 and g < 0.15 and b < 0.15  # noqa: E731 - three.js keeps colours in linear RGB
    assert shown["offending"] and all(red(r, g, b) and a == 1.0 for r, g, b, a in shown["offending"]), shown
    assert shown["others"] and all(not red(r, g, b) and a < 1.0 for r, g, b, a in shown["others"]), shown
    assert np.abs(_truth(server)[0] - q0).max() < 2e-3  # nothing moved
    _plan_pose(page, *TARGET_MM)  # a plan that goes: the red arm gives way to the goal arm
    _shown_plan(page)
    assert page.evaluate("armlab.view3d.refusalShown") is None
    page.click("#btn-plan-discard")
    assert page.errors == []


def test_with_preview_on_a_click_grab_waits_for_execute_then_runs_that_plan(page, server):
    """The page setting 'preview before moving': a click on a block in Click-grab mode plans the grab (the goal arm
    at the grasp, the path) and nothing moves (ground truth: joints, the blocks, over sim time); Execute runs that
    very plan (the station then refuses it as executed) and the block is in the gripper (ground truth)."""
    if not server.get("/api/calibration").get("calibrated"):
        server.post("/api/calibrate?wait=true", timeout_s=120)
    page.check("#preview-moves")
    page.wait_for_function("window.armlab.detections.some(d => d.is_cube && !d.occluded)", timeout=20_000)
    cubes = [d for d in page.evaluate("window.armlab.detections") if d["is_cube"] and not d.get("occluded")]
    cube = min(cubes, key=lambda d: abs(float(np.hypot(*d["position_m"][:2])) - 0.25))
    objects = server.get("/api/sim/truth")["objects"]
    block = min(objects, key=lambda o: float(np.linalg.norm(np.asarray(o["position_m"][:2]) - cube["position_m"][:2])))
    q0, _, t0 = _truth(server)
    enter_click_mode(page, "grab")
    page.mouse.click(*canvas_point(page, *cube["center_px"]))
    assert "nothing moves until Execute" in _result(page, "planned")
    shown = _shown_plan(page)
    q1, _, _ = _after_sim_time(server, t0 + 1.0)
    still = {o["id"]: o["position_m"] for o in server.get("/api/sim/truth")["objects"]}
    assert np.abs(q1 - q0).max() < 2e-3, "the arm moved before Execute"
    assert all(np.allclose(still[o["id"]], o["position_m"], atol=1e-3) for o in objects), "a block moved before Execute"
    assert server.get("/api/status")["state"] == "idle"
    page.click("#btn-plan-execute")
    status = server.wait_status(lambda s: (s.get("job") or {}).get("name") == "grab" and s["job"]["state"] != "running"
                                and s["state"] == "idle", 90.0, "the planned grab to end")
    assert status["job"]["state"] == "succeeded", status["job"]
    truth = server.get("/api/sim/truth")
    assert truth["gripper"]["holding_id"] == block["id"], truth["gripper"]
    again = server.request("POST", f"/api/plans/{shown['id']}/execute")
    assert again.status_code == 409 and again.json()["error"]["reason"] == "executed", again.text
    page.uncheck("#preview-moves")
    server.post("/api/drop?wait=true", {"position_m": block["position_m"][:2] + [0.0]}, timeout_s=120)  # as it was
    assert server.get("/api/sim/truth")["gripper"]["holding_id"] is None
    assert page.errors == []


def test_with_preview_on_a_jog_step_waits_for_execute_then_steps(page, server):
    """The same setting on the jog pad: +Z plans the step (the goal arm, the path) and nothing moves (ground truth over
    sim time); Execute raises the gripper by the chosen step (ground truth)."""
    page.check("#preview-moves")
    try:
        page.select_option("#jog-step", "0.025")
        q0, point0, t0 = _truth(server)
        page.click("[data-jog='z+']")
        assert "nothing moves until Execute" in _result(page, "planned")
        shown = _shown_plan(page)
        q1, point1, _ = _after_sim_time(server, t0 + 1.0)
        assert np.abs(q1 - q0).max() < 2e-3 and np.linalg.norm(point1 - point0) < 0.002, "the arm moved on +Z"
        page.click("#btn-plan-execute")
        assert "executing the plan" in _result(page, "sent")
        server.wait_status(lambda s: not s["moving"] and s["state"] == "idle", 30.0, "the step to end")
        q2, point2, _ = _truth(server)
        assert point2[2] - point0[2] == pytest.approx(0.025, abs=0.004), (point0, point2)
        assert np.linalg.norm(point2[:2] - point0[:2]) < 0.004, (point0, point2)
        assert np.abs(q2 - np.asarray(shown["joints"])).max() < 0.02, (q2, shown["joints"])
        assert page.errors == []
    finally:
        page.uncheck("#preview-moves")


STEP_PROGRAM_RAD = [[0.4, -0.2, 0.3, 0.6, 0.0], [0.0, 0.1, 0.2, 0.8, 0.3]]


def _paused(s) -> bool:
    repeat = ((s.get("job") or {}).get("extra") or {}).get("repeat") or {}
    return s["state"] == "repeat" and repeat.get("phase") == "paused" and not s["moving"]


def test_with_preview_on_a_paused_repeats_step_waits_for_execute_then_steps(page, server):
    """Single-stepping a paused repeat with the setting on: Step plans the job's next step (the goal arm and path in 3-D)
    and nothing moves (ground truth over sim time); Execute runs it: the arm stops at the goal shown (ground truth) and
    the job waits paused at the step after."""
    content = json.dumps({"name": "step-preview", "waypoints": [{"joints_rad": q, "gripper": "release"} for q in STEP_PROGRAM_RAD]})
    program = server.post("/api/programs/import", {"format": "json", "content": content})
    page.check("#preview-moves")
    try:
        server.request("POST", f"/api/programs/{program['id']}/repeat", json={"cycles": 1})
        server.post("/api/jobs/pause")
        server.wait_status(_paused, 60.0, "the repeat paused at rest")
        page.wait_for_function("!document.getElementById('btn-repeat-step').disabled", timeout=30_000)
        q0, _, t0 = _truth(server)
        page.click("#btn-repeat-step")
        assert "nothing moves until Execute" in _result(page, "planned")
        shown = _shown_plan(page)
        q1, _, _ = _after_sim_time(server, t0 + 1.0)
        assert np.abs(q1 - q0).max() < 2e-3, "the arm moved on Step"
        assert _paused(server.get("/api/status"))
        page.click("#btn-plan-execute")
        assert "executing the plan" in _result(page, "sent")
        server.wait_status(lambda s: _paused(s) and np.abs(np.subtract(s["joints_rad"], q0)).max() > 0.01, 60.0,
                           "the step to end, paused again")
        q2, _, _ = _truth(server)
        assert np.abs(q2 - np.asarray(shown["joints"])).max() < 0.02, (q2, shown["joints"])
        assert page.errors == []
    finally:
        page.uncheck("#preview-moves")
        server.request("POST", "/api/jobs/cancel")
        server.wait_status(lambda s: s["state"] == "idle", 60.0, "the repeat cancelled")
        server.request("DELETE", f"/api/programs/{program['id']}")
