"""`armlab serve` as a real subprocess on the simulation, for the benchmarks that measure the server from outside."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

REPO = Path(__file__).resolve().parents[1]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def start_server(port: int, token: str, db_path: Path, log_path: Path, level: int = 2, startup_timeout_s: float = 90.0,
                 extra_args: tuple[str, ...] = ()) -> subprocess.Popen:
    """Start `armlab serve` on 127.0.0.1:port with a pick_sort scene of `level` (seed 1), its output in log_path;
    returns once /api/health answers, or raises with the log's tail."""
    command = [sys.executable, "-m", "armlab.cli", "serve", "--port", str(port), "--token", token, "--db", str(db_path),
               "--event", "pick_sort", "--level", str(level), "--scene-seed", "1", *extra_args]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    with log_path.open("w") as log:
        process = subprocess.Popen(command, cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + startup_timeout_s
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError(f"server exited: {log_path.read_text()[-2000:]}")
        try:
            if httpx.get(f"http://127.0.0.1:{port}/api/health", timeout=1).status_code == 200:
                return process
        except httpx.HTTPError:
            time.sleep(0.2)
    process.kill()
    raise RuntimeError(f"server did not start within {startup_timeout_s:.0f} s")
