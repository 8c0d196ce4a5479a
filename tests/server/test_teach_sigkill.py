"""SIGKILL a real `armlab serve` (simulation) at random moments while teaching and saving: nothing the
API acknowledged is lost (issue 9 teach 1, issue 10 "must show").

Each recorded waypoint is committed to the database's teach draft before /api/teach/record answers, so
after the kill and a restart GET /api/teach/draft holds every acknowledged waypoint (at most one more:
the request in flight), in order, and /api/teach/start resumes them. teach/stop saves the program and
empties the draft in one transaction: after a kill during the save, the waypoints are in exactly one of
the two, never both, never partly. The waypoints are told apart by their dwell_s (the arm need not move).
"""

from __future__ import annotations

import random
import signal
import subprocess
import threading
import time
from pathlib import Path

import httpx
import pytest

import live

TOKEN = "sigkill-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


def _start(db_path: Path) -> tuple[subprocess.Popen, str]:
    return live.start_serve_process(TOKEN, db_path, live.serve_config(Path(db_path).parent))


def _kill(process: subprocess.Popen) -> None:
    process.send_signal(signal.SIGKILL)
    process.wait(15)


def _record_until_killed(base: str, acknowledged: list[float], first: int) -> None:
    """Record waypoints back to back (dwell_s = index / 1000) until the server dies; keep what was acknowledged."""
    with httpx.Client(base_url=base, timeout=5, headers=AUTH) as http:
        index = first
        while True:
            dwell_s = index / 1000.0
            try:
                response = http.post("/api/teach/record", json={"dwell_s": dwell_s})
            except httpx.HTTPError:
                return
            assert response.status_code == 200, response.text
            assert response.json()["dwell_s"] == dwell_s
            acknowledged.append(dwell_s)
            index += 1


def _draft_dwells(base: str) -> list[float]:
    draft = httpx.get(base + "/api/teach/draft", timeout=10).json()
    assert draft["skipped"] == []
    return [waypoint["dwell_s"] for waypoint in draft["waypoints"]]


@pytest.mark.parametrize("seed", [1, 2])
def test_sigkill_while_recording_and_saving_loses_nothing_acknowledged(tmp_path, seed):
    rng = random.Random(seed)
    db_path = tmp_path / "station.sqlite3"
    process, base = _start(db_path)
    try:
        assert httpx.post(base + "/api/teach/start", headers=AUTH, timeout=10).json()["state"] == "teach"
        acknowledged: list[float] = []
        recorder = threading.Thread(target=_record_until_killed, args=(base, acknowledged, 1), daemon=True)
        recorder.start()
        target = rng.randint(1, 30)
        live.wait_for(lambda: len(acknowledged) >= target, 30, 0.001)
        time.sleep(rng.uniform(0.0, 0.02))  # a random moment, likely mid-request: not synchronisation
        _kill(process)
        recorder.join(10)
        assert acknowledged, "nothing was acknowledged before the kill"
    finally:
        process.kill()

    process, base = _start(db_path)
    try:
        dwells = _draft_dwells(base)
        assert dwells[: len(acknowledged)] == acknowledged, (acknowledged, dwells)  # every acknowledged one, in order
        assert len(dwells) <= len(acknowledged) + 1  # plus at most the request in flight
        status = httpx.post(base + "/api/teach/start", headers=AUTH, timeout=10).json()
        assert status["state"] == "teach" and f"{len(dwells)} waypoints (draft resumed)" in status["detail"]

        # Now kill during the save: the waypoints end up in the program or in the draft, whole, never both.
        for index in range(len(dwells) + 1, len(dwells) + 4):
            assert httpx.post(base + "/api/teach/record", json={"dwell_s": index / 1000.0}, headers=AUTH, timeout=10).status_code == 200
        expected = _draft_dwells(base)
        saved: list[dict] = []

        def save() -> None:
            try:
                response = httpx.post(base + "/api/teach/stop", json={"name": f"killed {seed}"}, headers=AUTH, timeout=10)
                saved.append(response.json())
            except httpx.HTTPError:
                pass

        saver = threading.Thread(target=save, daemon=True)
        saver.start()
        time.sleep(rng.uniform(0.0, 0.03))  # a random moment around the save: not synchronisation
        _kill(process)
        saver.join(10)
    finally:
        process.kill()

    process, base = _start(db_path)
    try:
        programs = [p for p in httpx.get(base + "/api/programs", timeout=10).json()["data"] if p["name"] == f"killed {seed}"]
        draft = _draft_dwells(base)
        if saved:  # acknowledged: the program is there and the draft is empty
            assert len(programs) == 1 and draft == []
        assert (len(programs), draft) in ((1, []), (0, expected)), (programs, draft)
        if programs:
            assert [w["dwell_s"] for w in programs[0]["waypoints"]] == expected
    finally:
        process.terminate()
        try:
            process.wait(15)
        except subprocess.TimeoutExpired:
            process.kill()


def test_a_job_killed_by_sigkill_reads_interrupted_in_the_history_after_restart(tmp_path):
    """Issue 18 item 8: a job's row is written when it starts, so a SIGKILL mid-job leaves it; the next start
    marks it 'interrupted' (it was missing from /api/jobs/history)."""
    db_path = tmp_path / "station.sqlite3"
    process, base = _start(db_path)
    try:
        with httpx.Client(base_url=base, timeout=30, headers=AUTH) as http:
            content = ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n2,0.6,0.1,0.2,0.3,0,release\n"
                       "4,-0.6,0.1,0.2,0.3,0,release\n")
            program = http.post("/api/programs/import", json={"format": "csv", "content": content, "name": "loop"})
            assert program.status_code == 201, program.text
            started = http.post(f"/api/programs/{program.json()['id']}/repeat", json={"cycles": None})
            assert started.status_code == 202, started.text
            job_id = started.json()["job"]["id"]
            live.wait_for(lambda: http.get("/api/status").json()["moving"], 30)
    finally:
        _kill(process)
    process, base = _start(db_path)
    try:
        history = httpx.get(base + "/api/jobs/history", timeout=30).json()["data"]
        killed = [job for job in history if job["id"] == job_id]
        assert killed and killed[0]["state"] == "interrupted", history
        assert killed[0]["name"] == "repeat" and "stopped" in killed[0]["message"], killed
    finally:
        _kill(process)
