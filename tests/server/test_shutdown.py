"""Shutdown of a real `armlab serve` (issue 10 item 6): SIGTERM or Ctrl-C (SIGINT) while a job runs and a
`?wait=true` request waits on it: the process exits, the waiting request gets its answer, and the log says
which threads were joined. The bound is a hang detector (before the fix one such request held shutdown
for the job's whole length); the measured time is printed (-s) as a figure."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import pytest

import live

REPO = Path(__file__).resolve().parents[2]
TOKEN = "shutdown-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
HANG_S = 10.0


def _serve(tmp_path: Path, log_path: Path) -> tuple[subprocess.Popen, str]:
    port = live.free_port()
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    with log_path.open("w") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "armlab.cli", "serve", "--port", str(port), "--token", TOKEN, "--db", str(tmp_path / "db.sqlite3"),
             "--config", live.serve_config(tmp_path)],
            cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT, text=True,
        )
    base = f"http://127.0.0.1:{port}"

    def healthy() -> bool:
        try:
            return httpx.get(base + "/api/health", timeout=1).status_code == 200
        except httpx.HTTPError:
            return process.poll() is not None  # died: stop waiting, the assertion below says so

    live.wait_for(healthy, 90, 0.2)
    assert process.poll() is None, log_path.read_text()
    return process, base


def _long_repeat_job(client: httpx.Client) -> int:
    """Teach two far-apart waypoints; returns the program id."""
    assert client.post("/api/teach/start", headers=AUTH).status_code == 200
    for q in ([0.8, 0.2, 0.1, 0.3, 0.0], [-0.8, 0.0, 0.2, 0.5, 0.4]):
        response = client.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": q, "moving_time_s": 2.0}, headers=AUTH)
        assert response.status_code == 200, response.text
        assert client.post("/api/teach/record", headers=AUTH).status_code == 200
    return client.post("/api/teach/stop", json={"name": "back and forth"}, headers=AUTH).json()["id"]


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "SIGINT"])
def test_signal_mid_job_with_a_waiting_request_exits_promptly_and_joins_threads(tmp_path, sig):
    log_path = tmp_path / "serve.log"
    process, base = _serve(tmp_path, log_path)
    waited: dict = {}
    try:
        with httpx.Client(base_url=base, timeout=60) as client:
            program_id = _long_repeat_job(client)

            def wait_for_the_job() -> None:  # a job of 100 cycles x 2 moves: minutes long
                try:
                    waited["response"] = httpx.post(
                        f"{base}/api/programs/{program_id}/repeat", params={"wait": "true"}, json={"cycles": 100}, headers=AUTH, timeout=60
                    )
                except httpx.HTTPError as error:
                    waited["error"] = error

            waiter = threading.Thread(target=wait_for_the_job, daemon=True)
            waiter.start()
            live.wait_for(lambda: client.get("/api/status").json()["state"] == "repeat", 20)
            live.wait_for(lambda: client.get("/api/status").json()["moving"], 20)
        signalled = time.monotonic()
        process.send_signal(sig)
        process.wait(HANG_S)
        exit_s = time.monotonic() - signalled
        waiter.join(HANG_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(10)
    log = log_path.read_text()
    print(f"\n{signal.Signals(sig).name}: exited {exit_s:.2f} s after the signal (job running, one ?wait=true request open)")
    assert exit_s < HANG_S
    assert not waiter.is_alive(), "the waiting request never returned"
    if "response" in waited:
        assert waited["response"].json()["job"]["state"] in ("cancelled", "failed"), waited["response"].text
    assert "threads joined: " in log and "still running" not in log, log[-3000:]
    assert "Traceback" not in log, log[-3000:]
    for name in ("job-repeat", "station-camera", "station-perception", "station-telemetry", "station-watch", "sim-physics"):
        assert name in log.split("threads joined: ")[1], log[-3000:]
