"""The report's swap task taught and repeated through the REST calls the page makes (issue 9, must show).

Two large blocks at (−100, 225) and (100, 225) mm are exchanged through (250, 75) mm: A → C, B → A,
C → B. The program is taught with pose moves, gripper commands and teach/record (a gripper step is a
record at the same pose after the gripper command), saved, then repeated for 10 cycles. After every
cycle (the job's "cycle k done" event, read in the job's thread while the fast-mode physics is paused)
the simulation's ground truth must show the blocks exchanged within 10 mm, both upright on the board.
The station runs synchronously on the fast-mode simulation, so the 10 cycles take seconds, not minutes.
"""

from __future__ import annotations

import math

import httpx
import numpy as np
import pytest

import live
from server.app import create_app

TOKEN = "swap-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
A, B, C = (-0.100, 0.225), (0.100, 0.225), (0.250, 0.075)
EDGE_M = 0.038
ABOVE_Z_M = 0.15
GRASP_Z_M = EDGE_M - 0.015  # 15 mm below the top face
RELEASE_Z_M = GRASP_Z_M + 0.005  # the block's bottom 5 mm above the board
CYCLES = 10
TOLERANCE_M = 0.010


class SyncStation:
    """create_app's station factory: a synchronous Station on a fast-mode simulation (physics advances only
    while the station waits), with the cell kept for ground truth."""

    def __init__(self, db_path) -> None:
        from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
        from armlab.kinematics import load_arm
        from armlab.station import Station, StationConfig

        self.cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=0))
        self.cell.start()
        config = StationConfig(database_path=str(db_path))
        self.station = Station(self.cell.arm, self.cell.gripper, self.cell.camera, model=load_arm(config.arm), config=config,
                               sim=self.cell, backend="sim", synchronous=True)
        self.station.start()

    def close(self) -> dict:
        report = self.station.close()
        self.cell.close()
        return report


@pytest.fixture()
def served(tmp_path):
    made: list[SyncStation] = []

    def factory():
        made.append(SyncStation(tmp_path / "swap.sqlite3"))
        return made[-1]

    app = create_app(station_factory=factory, token=TOKEN)
    with live.serve(app) as url, httpx.Client(base_url=url, timeout=120.0, headers=AUTH) as http:
        yield http, made[0]


def _ok(response) -> dict:
    assert response.status_code in (200, 201, 202), response.text
    return response.json()


def _record_at(http, xy, z_m, gripper: str) -> None:
    _ok(http.post("/api/arm/pose", params={"wait": "true"},
                  json={"position_m": [xy[0], xy[1], z_m], "pitch_rad": math.pi / 2, "yaw_rad": 0.0}))
    _ok(http.post("/api/gripper", params={"wait": "true"}, json={"action": gripper}))
    _ok(http.post("/api/teach/record"))


def _teach_transfer(http, source, target) -> None:
    """Record: above the source, down, grasp (a gripper step), up, above the target, down, release, up."""
    _record_at(http, source, ABOVE_Z_M, "release")
    _record_at(http, source, GRASP_Z_M, "release")
    _record_at(http, source, GRASP_Z_M, "grasp")
    _record_at(http, source, ABOVE_Z_M, "grasp")
    _record_at(http, target, ABOVE_Z_M, "grasp")
    _record_at(http, target, RELEASE_Z_M, "grasp")
    _record_at(http, target, RELEASE_Z_M, "release")
    _record_at(http, target, ABOVE_Z_M, "release")


def _blocks(cell) -> dict:
    return {o["id"]: o for o in cell.truth()["objects"]}


def _upright_on_board(block) -> bool:
    w, x, y, z = block["quat_wxyz"]
    z_axis_z = 1.0 - 2.0 * (x * x + y * y)  # the body z axis' world z component
    return z_axis_z > math.cos(math.radians(15)) and abs(block["position_m"][2] - EDGE_M / 2) < 0.006


def test_teach_the_swap_and_repeat_it_ten_times_blocks_exchanged_after_every_cycle(served):
    http, made = served
    cell = made.cell
    objects = [
        {"id": "first", "type": "block", "color": "red", "size": "large", "position_m": [A[0], A[1], EDGE_M / 2], "yaw_rad": 0.0},
        {"id": "second", "type": "block", "color": "blue", "size": "large", "position_m": [B[0], B[1], EDGE_M / 2], "yaw_rad": 0.0},
    ]
    _ok(http.post("/api/sim/scene", json={"objects": objects}))
    assert _ok(http.post("/api/teach/start", json={"discard_draft": True}))["state"] == "teach"
    _teach_transfer(http, A, C)
    _teach_transfer(http, B, A)
    _teach_transfer(http, C, B)
    program = _ok(http.post("/api/teach/stop", json={"name": "swap"}))
    assert len(program["waypoints"]) == 24
    after_teaching = _blocks(cell)  # teaching moved the blocks too: they are exchanged once already
    assert np.allclose(after_teaching["first"]["position_m"][:2], B, atol=TOLERANCE_M)
    assert np.allclose(after_teaching["second"]["position_m"][:2], A, atol=TOLERANCE_M)

    seen: list[dict] = []

    def on_event(event: dict) -> None:  # runs in the job's thread: the fast-mode physics waits for it
        if event["message"].startswith("repeat: cycle "):
            seen.append(_blocks(cell))

    made.station.events.add_listener(on_event)
    try:
        job = _ok(http.post(f"/api/programs/{program['id']}/repeat", params={"wait": "true"},
                            json={"cycles": CYCLES, "speed_percent": 100}))["job"]
    finally:
        made.station.events.remove_listener(on_event)
    assert job["state"] == "succeeded", job
    assert len(seen) == CYCLES
    for cycle, blocks in enumerate(seen, start=1):
        # the blocks started the repeat exchanged (first at B): odd cycles bring them back, even ones exchange again
        first_at, second_at = (A, B) if cycle % 2 == 1 else (B, A)
        for block_id, spot in (("first", first_at), ("second", second_at)):
            block = blocks[block_id]
            error_m = float(np.hypot(block["position_m"][0] - spot[0], block["position_m"][1] - spot[1]))
            assert error_m <= TOLERANCE_M, f"cycle {cycle}: {block_id} is {error_m * 1000:.1f} mm from {spot}"
            assert _upright_on_board(block), f"cycle {cycle}: {block_id} dropped or tipped: {block}"
    status = http.get("/api/status").json()
    assert status["state"] == "idle" and np.allclose(status["joints_rad"], 0.0, atol=0.02)  # home at the end
