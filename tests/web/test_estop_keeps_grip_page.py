"""E-stop pressed on the page while the arm carries a block (issue 21, broken item 5, page side): the block
stays in the gripper at the height it was carried (the simulation's ground truth), before: the fingers let go
and it fell ~40 mm. Real `armlab serve` (RX200, pick_sort scene), real Chromium, the page's E-STOP button."""

from __future__ import annotations

import time

import pytest
from browser_helpers import open_page, ready_idle, wait_frames

pytestmark = pytest.mark.browser


def _objects(server) -> dict:
    return {o["id"]: o for o in server.get("/api/sim/truth")["objects"]}


def test_estop_button_while_carrying_keeps_the_block(browser, server):
    ready_idle(server)
    block_id, block = next((k, o) for k, o in _objects(server).items() if o.get("type", "block") == "block")
    x, y, z = block["position_m"]
    page = open_page(browser, f"{server.base_url}/?token={server.token}")
    try:
        wait_frames(page, 1)
        grab = server.request("POST", "/api/grab?wait=true", {"position_m": [x, y, 2 * z]}, timeout_s=120)
        assert grab.status_code == 200 and grab.json()["job"]["state"] == "succeeded", grab.text
        assert server.get("/api/sim/truth")["gripper"]["holding_id"] == block_id
        server.post("/api/drop", {"position_m": [-x, y, 0.0]})
        deadline = time.monotonic() + 30
        while _objects(server)[block_id]["position_m"][2] < z + 0.05:  # carried up and away
            assert time.monotonic() < deadline, "the block was never lifted"
        page.click("#btn-estop")
        server.wait_status(lambda s: s["state"] == "estop" and not s["moving"], 5.0, "e-stop")
        halted_z = _objects(server)[block_id]["position_m"][2]
        page.wait_for_function("document.getElementById('state-badge').textContent === 'estop'", timeout=5_000)
        end = time.monotonic() + 1.5  # a released block reaches the board well within this
        while time.monotonic() < end:
            truth = server.get("/api/sim/truth")
            assert truth["gripper"]["holding_id"] == block_id, f"the gripper let go: {truth['gripper']}"
        assert abs(_objects(server)[block_id]["position_m"][2] - halted_z) < 0.005
    finally:
        page.close()
        server.post("/api/reset")
        server.post("/api/gripper?wait=true", {"action": "release"})
        server.post("/api/arm/home?wait=true", {"moving_time_s": 1.5})
        server.post("/api/sim/scene", {"event": "pick_sort", "level": 1, "seed": 3})  # the session's scene (conftest)
