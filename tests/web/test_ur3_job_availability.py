"""A station serving the UR3 suction workcell does not offer jobs that cannot run on it (real
`armlab serve --workcell ur3_suction`, real HTTP, real Chromium): GET /api/auto/jobs marks to_the_sky
(needs fingers: side grasps), pick_stack (board tags outside the judge's gripper box) and line_up (the
RX200's reach band) unavailable with the reason, the others available; POST /api/auto of to_the_sky on a
calibrated station is a 422 naming the job, the workcell and the gripper it needs, the station stays
idle and nothing moves (simulation truth); the page's Competition panel lists it disabled, never
selected. The workcell's gripper type is read from config/workcells/ur3_suction.yaml here."""

from __future__ import annotations

import math

import pytest
import yaml
from browser_helpers import REPO, open_page, ready_idle

pytestmark = pytest.mark.browser

GRIPPER = yaml.safe_load((REPO / "config/workcells/ur3_suction.yaml").read_text())["gripper"]["type"]
UNAVAILABLE = {"to_the_sky", "pick_stack", "line_up"}
AVAILABLE = {"pick_sort", "stack_high", "sort_stack", "clear_table", "sort_by_tag", "stack_here"}


def test_the_job_list_says_which_jobs_the_ur3_runs(ur3_server):
    jobs = {job["name"]: job for job in ur3_server.get("/api/auto/jobs")["data"]}
    assert {name for name, job in jobs.items() if not job["available"]} == UNAVAILABLE
    assert AVAILABLE <= {name for name, job in jobs.items() if job["available"]}
    assert all(jobs[name]["unavailable_reason"] is None for name in AVAILABLE)
    sky = jobs["to_the_sky"]["unavailable_reason"]
    assert GRIPPER == "suction" and "fingers" in sky and GRIPPER in sky, sky
    assert "gripper box" in jobs["pick_stack"]["unavailable_reason"]
    assert "reach" in jobs["line_up"]["unavailable_reason"]


def _still(server) -> dict:
    truth = server.get("/api/sim/truth")
    return {"objects": {o["id"]: o["position_m"] for o in truth["objects"]}, "cup": truth["gripper"]["position_m"],
            "joints": server.get("/api/status")["joints_rad"]}


def _same(a: dict, b: dict, tol_m: float = 1e-3) -> None:
    assert a["objects"].keys() == b["objects"].keys()
    for name, position in a["objects"].items():
        assert math.dist(position, b["objects"][name]) < tol_m, f"{name} moved"
    assert math.dist(a["cup"], b["cup"]) < tol_m, "the cup moved"
    assert max(abs(p - q) for p, q in zip(a["joints"], b["joints"])) < 5e-3, "the arm moved"


def test_an_unsupported_job_is_422_naming_it_and_nothing_moves(ur3_server):
    server = ur3_server
    ready_idle(server)
    calibration = server.post("/api/calibrate?wait=true", timeout_s=120)  # only the workcell check can refuse it
    assert calibration["job"]["state"] == "succeeded", calibration
    before, job_before = _still(server), server.get("/api/jobs/current")["job"]["id"]
    response = server.request("POST", "/api/auto", json={"job": "to_the_sky", "level": 1})
    assert response.status_code == 422, response.text
    message = response.json()["error"]["message"]
    assert "to_the_sky" in message and "ur3_suction" in message and "fingers" in message, message
    status = server.get("/api/status")
    assert status["state"] == "idle" and server.get("/api/jobs/current")["job"]["id"] == job_before
    _same(before, _still(server))
    server.wait_status(lambda s: s["state"] == "idle" and not s["moving"], 5.0, "still idle")
    _same(before, _still(server))


def test_the_competition_panel_does_not_offer_them(ur3_server, browser):
    page = open_page(browser, f"{ur3_server.base_url}/?token={ur3_server.token}")
    try:
        page.wait_for_function("document.querySelectorAll('#comp-job option').length >= 9", timeout=20_000)
        options = page.eval_on_selector_all(
            "#comp-job option", "os => os.map(o => ({value: o.value, disabled: o.disabled, title: o.title}))")
        offered = {o["value"] for o in options if not o["disabled"]}
        assert offered.isdisjoint(UNAVAILABLE) and AVAILABLE <= offered, options
        sky = next(o for o in options if o["value"] == "to_the_sky")
        assert sky["disabled"] and "fingers" in sky["title"], sky
        assert page.eval_on_selector("#comp-job", "s => s.value") in AVAILABLE
        reasons = page.eval_on_selector_all("#comp-unavailable li", "ls => ls.map(l => [l.dataset.job, l.innerText])")
        assert {job for job, _ in reasons} == UNAVAILABLE and page.is_visible("#comp-unavailable"), reasons
        assert "fingers" in dict(reasons)["to_the_sky"], reasons
        assert page.errors == []
    finally:
        page.close()
