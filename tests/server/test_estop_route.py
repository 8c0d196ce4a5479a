"""POST /api/estop over real HTTP never waits behind other requests (issue 10 item 4): with every worker
thread of the server blocked in `?wait=true` moves, the e-stop still answers, halts the arm, and the
waiting requests then return. The bound below is a hang detector (the moves take 10 s); the latency
figures are in bench/estop.py."""

from __future__ import annotations

import threading

import httpx
import numpy as np

import live

TOKEN = "estop-route-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
BLOCKERS = 48  # more than the server's 40 worker threads
HANG_S = 4.0  # the blocked moves last 10 s: an e-stop that waited for a thread would take that long


cell, url = live.module_fixtures(seed=11, token=TOKEN)


def test_estop_answers_while_every_worker_thread_waits_on_a_move(url, cell):
    goal = {"q_rad": [0.8, 0.3, 0.2, 0.4, 0.5], "moving_time_s": 10.0}
    results: list[int] = []
    started = threading.Barrier(BLOCKERS + 1)

    def blocked_move() -> None:
        with httpx.Client(base_url=url, timeout=60) as client:
            started.wait()
            results.append(client.post("/api/arm/joints", params={"wait": "true"}, json=goal, headers=AUTH).status_code)

    threads = [threading.Thread(target=blocked_move, daemon=True) for _ in range(BLOCKERS)]
    for thread in threads:
        thread.start()
    started.wait()
    live.wait_for(lambda: np.linalg.norm(cell.arm.read_joint_state().velocity_rad_s) > 0.05, 20, 0.01)
    with httpx.Client(base_url=url, timeout=HANG_S) as client:
        status = client.post("/api/estop", headers=AUTH).json()
    assert status["state"] == "estop"
    assert not cell.arm.is_moving()
    for thread in threads:
        thread.join(HANG_S)
    assert not any(thread.is_alive() for thread in threads), "waiting requests outlived the e-stop"
    assert len(results) == BLOCKERS and all(code in (200, 409) for code in results), results
    with httpx.Client(base_url=url, timeout=10) as client:
        assert client.post("/api/reset", headers=AUTH).json()["state"] == "idle"
