"""Browser-test fixtures: the real `armlab serve` (simulated workcell) as a subprocess on a free port,
real Chromium (Debian's /usr/bin/chromium) driven by Playwright, and a small REST helper."""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import httpx
import pytest

from browser_helpers import OPERATOR

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))
import live  # noqa: E402  (tests/server/live.py: the test servers' config, free ports)

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SERVER_START_TIMEOUT_S = 90.0
# A fixed scene: three large cubes (R, G, B) in reach in the positive half-plane.
SCENE_ARGS = ["--event", "pick_sort", "--level", "1", "--scene-seed", "3", "--seed", "1"]


def armlab_command() -> list[str]:
    """The venv's console script when present, else the module form with this interpreter."""
    script = REPO / ".venv" / "bin" / "armlab"
    if script.exists():
        return [str(script)]
    found = shutil.which("armlab")
    return [found] if found else [sys.executable, "-m", "armlab.cli"]


@dataclass
class Server:
    """A running `armlab serve`: base URL, its control token, and a REST helper. One HTTP client for all its
    calls: httpx builds a verified TLS context for every client it makes (its CA bundle read anew, 45-160 ms of
    CPU), which a test polling the status ten times a second paid at every poll."""

    base_url: str
    token: str
    process: subprocess.Popen
    log_path: Path
    http: httpx.Client

    def request(self, method: str, path: str, json: dict | None = None, timeout_s: float = 30.0) -> httpx.Response:
        headers = {"Authorization": f"Bearer {self.token}", "X-Armlab-Controller": OPERATOR}  # as the test pages
        return self.http.request(method, self.base_url + path, json=json, headers=headers, timeout=timeout_s)

    def get(self, path: str) -> dict:
        response = self.request("GET", path)
        response.raise_for_status()
        return response.json()

    def post(self, path: str, json: dict | None = None, timeout_s: float = 30.0) -> dict:
        response = self.request("POST", path, json=json if json is not None else {}, timeout_s=timeout_s)
        assert response.status_code < 300, f"POST {path} -> {response.status_code}: {response.text}"
        return response.json() if response.content else {}

    def log_tail(self, n_chars: int = 3000) -> str:
        try:
            return self.log_path.read_text(errors="replace")[-n_chars:]
        except OSError:
            return ""

    def wait_status(self, predicate, timeout_s: float, what: str) -> dict:
        """Poll GET /api/status until predicate(status) holds; fail naming `what` otherwise."""
        deadline = time.monotonic() + timeout_s
        status = {}
        while time.monotonic() < deadline:
            status = self.get("/api/status")
            if predicate(status):
                return status
            time.sleep(0.1)
        raise AssertionError(f"timed out after {timeout_s} s waiting for {what}; last status: {status}")


@contextlib.contextmanager
def running_server(folder: Path, args: tuple[str, ...] = tuple(SCENE_ARGS), time_scale: float = 1.0) -> Iterator[Server]:
    """A fresh `armlab serve` (its own port, token and SQLite file in `folder`; config/station.yaml with the
    tests' camera, live.serve_config) until the block ends; args: the scene and workcell options (default: the RX200
    workcell with SCENE_ARGS); time_scale: the simulation's pace (live.FAST_TIME_SCALE for whole jobs)."""
    port = live.free_port()
    config_path = live.serve_config(folder, time_scale)  # the tests' camera rate and watchdog, as for the HTTP tests' servers
    token = secrets.token_urlsafe(16)
    log_path = folder / "serve.log"
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    # this checkout's armlab, server and web/ first: the venv's editable install may point at another checkout (a git
    # worktree sharing the main checkout's .venv served that checkout's page and code)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))
    db_path = folder / "armlab.sqlite3"  # a fresh store: no calibration or programs from earlier runs
    with log_path.open("wb") as log:
        process = subprocess.Popen(
            [*armlab_command(), "serve", "--host", "127.0.0.1", "--port", str(port), f"--token={token}",
             "--config", config_path, "--db", str(db_path), *args],
            cwd=REPO,
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
    srv = Server(f"http://127.0.0.1:{port}", token, process, log_path, httpx.Client())
    try:
        deadline = time.monotonic() + SERVER_START_TIMEOUT_S
        while True:
            if process.poll() is not None:
                raise RuntimeError(f"armlab serve exited with {process.returncode}:\n{srv.log_tail()}")
            try:
                if srv.http.get(srv.base_url + "/api/health", timeout=1.0).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(f"armlab serve not healthy after {SERVER_START_TIMEOUT_S} s:\n{srv.log_tail()}")
            time.sleep(0.25)
        yield srv
    finally:
        srv.http.close()
        process.terminate()
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=5)


class SharedServer:
    """The browser tests' one `armlab serve` (SCENE_ARGS), started when a test module first asks for it and stopped
    after the last browser test the process runs (pytest_runtest_teardown below): a simulated station keeps about
    half a core busy while it runs, and a process that runs other tests after the browser tests (a pytest-xdist
    worker) would otherwise carry it to the end. A later browser test starts a new one."""

    def __init__(self, tmp_path_factory) -> None:
        self._tmp_path_factory = tmp_path_factory
        self._stack: contextlib.ExitStack | None = None
        self._server: Server | None = None

    def get(self) -> Server:
        if self._server is None:
            stack = contextlib.ExitStack()
            self._server = stack.enter_context(running_server(self._tmp_path_factory.mktemp("server")))
            self._stack = stack
        return self._server

    def stop(self) -> None:
        stack, self._stack, self._server = self._stack, None, None
        if stack is not None:
            stack.close()


SHARED_SERVER = pytest.StashKey[SharedServer]()
WEB_TESTS = Path(__file__).resolve().parent


@pytest.fixture(scope="session")
def _shared_server(request, tmp_path_factory) -> Iterator[SharedServer]:
    shared = request.config.stash[SHARED_SERVER] = SharedServer(tmp_path_factory)
    try:
        yield shared
    finally:
        shared.stop()
        del request.config.stash[SHARED_SERVER]


@pytest.fixture(scope="module")
def server(_shared_server) -> Server:
    """The shared `armlab serve` (state carries over from module to module: each test brings it to what it needs)."""
    return _shared_server.get()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    """After the last browser test in a row (the next test is elsewhere, or none) and its fixtures' teardown: stop
    the shared server (see SharedServer)."""
    result = yield
    if nextitem is None or WEB_TESTS not in Path(nextitem.path).resolve().parents:
        shared = item.config.stash.get(SHARED_SERVER, None)
        if shared is not None:
            shared.stop()
    return result


@pytest.fixture(scope="module")
def ur3_server(tmp_path_factory) -> Iterator[Server]:
    """`armlab serve --workcell ur3_suction` (the UR3 with its suction cup) for one test module, at the fast pace (its
    tests run jobs and jog steps; none times a hold-to-run or a heartbeat)."""
    with running_server(tmp_path_factory.mktemp("ur3"), ("--workcell", "ur3_suction", "--seed", "1"), live.FAST_TIME_SCALE) as srv:
        yield srv


@pytest.fixture(scope="session")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield chromium
        finally:
            chromium.close()
