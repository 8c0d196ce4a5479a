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
        assert httpx.post(base + "/api/estop").status_code == 401
        status = httpx.post(base + "/api/estop", headers={"Authorization": f"Bearer {token}"}).json()
        assert status["state"] == "estop"
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
