"""`armlab serve` as a real subprocess: prints the ready-to-open URL with a generated token, binds
127.0.0.1, serves the page and the API, and streams without per-message compression."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import httpx
import psutil
from websockets.sync.client import connect

import live

REPO = Path(__file__).resolve().parents[2]


def test_serve_prints_token_url_and_streams_uncompressed(tmp_path):
    port = live.free_port()
    env = {key: value for key, value in os.environ.items() if key != "ARMLAB_TOKEN"}
    env.setdefault("MUJOCO_GL", "egl")
    process = subprocess.Popen(
        [sys.executable, "-m", "armlab.cli", "serve", "--port", str(port), "--db", str(tmp_path / "db.sqlite3")],
        cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        first_lines = [process.stdout.readline() for _ in range(2)]
        match = re.search(rf"http://127\.0\.0\.1:{port}/\?token=(\S+)", "".join(first_lines))
        assert match, first_lines
        token = match.group(1)
        base = f"http://127.0.0.1:{port}"
        live.wait_for(lambda: _healthy(base), 60, 0.2)
        page = httpx.get(base + "/")
        assert page.status_code == 200 and "<html" in page.text.lower()
        assert httpx.post(base + "/api/reset").status_code == 401
        status = httpx.post(base + "/api/estop").json()  # stopping never needs the token (issue 9 item 3)
        assert status["state"] == "estop"
        assert httpx.post(base + "/api/reset", headers={"Authorization": f"Bearer {token}"}).json()["state"] == "idle"
        with connect(f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, close_timeout=2) as ws:  # offers deflate
            assert "permessage-deflate" not in (ws.response.headers.get("Sec-WebSocket-Extensions") or "")
            assert '"can_control": true' in ws.recv(timeout=10)
        connections = [c for c in psutil.Process(process.pid).net_connections() if c.status == "LISTEN"]
        assert connections and all(c.laddr.ip == "127.0.0.1" for c in connections)
    finally:
        process.terminate()
        try:
            process.wait(15)
        except subprocess.TimeoutExpired:
            process.kill()


def _healthy(base: str) -> bool:
    try:
        return httpx.get(base + "/api/health", timeout=1).status_code == 200
    except httpx.HTTPError:
        time.sleep(0.1)
        return False


def test_the_token_shows_only_in_the_printed_url_never_in_log_lines(tmp_path):
    """Access logs at info level carry /?token=… and /ws?token=… requests: redacted (issue 10, item 8)."""
    port = live.free_port()
    token = "secret-" + os.urandom(8).hex()
    log_path = tmp_path / "serve.log"
    env = {key: value for key, value in os.environ.items() if key != "ARMLAB_TOKEN"}
    env.setdefault("MUJOCO_GL", "egl")
    with log_path.open("w") as log:
        process = subprocess.Popen(
            [sys.executable, "-m", "armlab.cli", "serve", "--port", str(port), "--token", token, "--log-level", "info",
             "--db", str(tmp_path / "db.sqlite3")],
            cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT, text=True,
        )
    try:
        base = f"http://127.0.0.1:{port}"
        live.wait_for(lambda: _healthy(base), 60, 0.2)
        assert httpx.get(f"{base}/?token={token}").status_code == 200
        assert httpx.get(f"{base}/api/status?view=1&token={token}&x=2").status_code == 200
        with connect(f"ws://127.0.0.1:{port}/ws?token={token}", open_timeout=10, close_timeout=2) as ws:
            assert '"can_control": true' in ws.recv(timeout=10)
        live.wait_for(lambda: "/ws?token=" in log_path.read_text(), 10)  # the websocket line was written
    finally:
        process.terminate()
        try:
            process.wait(15)
        except subprocess.TimeoutExpired:
            process.kill()
    text = log_path.read_text()
    assert text.count(token) == 1, text  # the printed URL, nowhere else
    assert f"http://127.0.0.1:{port}/?token={token}" in text.splitlines()[1]
    assert "GET /?token=[redacted]" in text and "token=[redacted]&x=2" in text and "/ws?token=[redacted]" in text


def test_a_damaged_database_stops_serve_with_one_line_naming_it_and_the_backup(tmp_path):
    from armlab.store import Store, Waypoint

    db = tmp_path / "station.sqlite3"
    Store(db, backups=3).save_program("keep me", [Waypoint((0.0, 0.1, 0.2, 0.3, 0.4), "grasp")])
    Store(db, backups=3)  # a good start: backs the program up to .bak1
    db.write_bytes(b"this is not a database" * 100)
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    result = subprocess.run(
        [sys.executable, "-m", "armlab.cli", "serve", "--port", str(live.free_port()), "--db", str(db)],
        cwd=REPO, env=env, capture_output=True, text=True, timeout=120,
    )
    assert result.returncode != 0
    lines = [line for line in (result.stdout + result.stderr).splitlines() if line.strip()]
    assert len(lines) == 1, lines
    assert str(db) in lines[0] and f"{db}.bak1" in lines[0] and "damaged" in lines[0]
    assert [p.name for p in Store(f"{db}.bak1").list_programs()] == ["keep me"]
