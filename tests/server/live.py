"""Helpers for tests over real HTTP: a simulated station shared by a module, a real uvicorn server on a
free 127.0.0.1 port in a thread, and a factory that lets one simulation serve several app lifetimes."""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import httpx
import pytest
import uvicorn

from armlab.station import Station, StationConfig

REPO = Path(__file__).resolve().parents[2]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


# The tests' real-time cells render TEST_CAMERA_FPS frames a second, not the product's 30: a 1280x720 render takes
# ~55 ms of CPU on llvmpipe (no GPU on CI), so a 30 fps camera renders back to back and keeps one of the machine's
# two cores busy for as long as its module runs, slowing every other thread of the test. 5 fps is the station's
# perception rate (perception_rate_hz 5): every perception pass still gets a frame of its own, taken up to 200 ms
# before it (at 30 fps, 33 ms), and every command that needs a picture taken after an event waits for one
# (Station.frame_after); tests of the frame clock itself choose their own rate (test_sim_workcell,
# test_camera_contract). 10 -> 5 fps: the whole suite at load 16-26 passed (less ~1.5 min of CPU, one fewer render
# of 55 ms a 200 ms in every live module).
TEST_CAMERA_FPS = 5.0
# Simulated seconds a wall second for modules whose tests wait on whole jobs and motions (the product runs at 1; a
# scaled clock is still the real physics, the servos at their control period): tests of the pace itself, of wall-clock
# deadlines (hold-to-run, heartbeats, watchdogs) and of e-stop timing keep the real-time pace.
FAST_TIME_SCALE = 3.0
TEST_CAMERA_TIMEOUT_S = 10.0


def serve_config(folder, time_scale: float = 1.0) -> str:
    """A copy of config/station.yaml in `folder` with the simulated camera at TEST_CAMERA_FPS (and the physics at
    time_scale, see FAST_TIME_SCALE), for the tests' `armlab serve --config` subprocesses (same reason as above);
    returns its path."""
    from pathlib import Path

    import yaml

    from armlab.config import config_dir

    config = yaml.safe_load((config_dir() / "station.yaml").read_text())
    config["sim"] = {**config.get("sim", {}), "camera_fps": TEST_CAMERA_FPS, "time_scale": time_scale}
    # A loaded machine can starve the simulated camera's render thread for seconds; the product's 2 s watchdog is
    # for real cameras (a shared test server faulted mid-test at load 13); the camera-loss tests set their own.
    config["camera_timeout_s"] = TEST_CAMERA_TIMEOUT_S
    path = Path(folder) / "station_test_fps.yaml"
    path.write_text(yaml.safe_dump(config))
    return str(path)


def start_serve_process(token: str, db_path, config_path, *extra_args: str) -> tuple[subprocess.Popen, str]:
    """A real `armlab serve` subprocess (this interpreter, the checkout as its folder, no ARMLAB_TOKEN inherited) on a
    free port, waited for until healthy: (process, base URL). The caller ends it (the SIGKILL tests kill it)."""
    port = free_port()
    env = {key: value for key, value in os.environ.items() if key != "ARMLAB_TOKEN"}
    env.setdefault("MUJOCO_GL", "egl")
    process = subprocess.Popen(
        [sys.executable, "-m", "armlab.cli", "serve", "--port", str(port), "--token", token, "--db", str(db_path),
         "--config", str(config_path), *extra_args],
        cwd=REPO, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    base = f"http://127.0.0.1:{port}"
    with httpx.Client() as http:

        def healthy() -> bool:
            try:
                return http.get(base + "/api/health", timeout=1).status_code == 200
            except httpx.HTTPError:
                return False

        try:
            wait_for(lambda: healthy() or process.poll() is not None, 90, 0.2)
        except AssertionError:
            process.kill()
            raise
    assert process.poll() is None, "armlab serve exited at start-up"
    return process, base


def start_cell(seed: int = 0, camera_fps: float = TEST_CAMERA_FPS, time_scale: float = 1.0):
    """A real-time SimWorkcell (camera at camera_fps, physics at time_scale simulated seconds a wall second), started."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=True, seed=seed, camera_fps=camera_fps, time_scale=time_scale))
    cell.start()
    return cell


def make_station(cell, db_path, store=None, perception_config=None, **config_overrides) -> Station:
    """A started Station on `cell` with its own database file (store: a Store instance, default the real one on
    db_path; perception_config: default the shipped one), with the tests' camera watchdog unless given (at load 20 a
    CPU-starved camera thread read as lost after 2 s). The one test station builder of tests/server and tests/station."""
    from armlab.kinematics import load_arm

    config_overrides.setdefault("camera_timeout_s", TEST_CAMERA_TIMEOUT_S)
    config = StationConfig(database_path=str(db_path), **config_overrides)
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=config, store=store, sim=cell,
                      backend="sim", perception_config=perception_config)
    station.start()
    return station


class StationOnCell:
    """What create_app's station_factory returns: a fresh Station on the shared cell; close() keeps the cell."""

    def __init__(self, cell, db_path, **config_overrides) -> None:
        self.station = make_station(cell, db_path, **config_overrides)

    def close(self) -> None:
        self.station.close()


@contextlib.contextmanager
def station_server(cell, db_path, token: str, **app_options):
    """A real server (see serve) whose app builds a fresh Station on `cell` with its own database; yields the URL."""
    from server.app import create_app

    app = create_app(station_factory=lambda: StationOnCell(cell, db_path), token=token, **app_options)
    with serve(app) as url:
        yield url


def module_fixtures(seed: int, token: str, time_scale: float = 1.0, camera_fps: float = TEST_CAMERA_FPS, **app_options):
    """The module-scoped `cell` (a started real-time simulation) and `url` (a real server on it) fixtures of a
    test module: `cell, url = live.module_fixtures(seed=3, token=TOKEN)`."""

    @pytest.fixture(scope="module")
    def cell():
        started = start_cell(seed, camera_fps=camera_fps, time_scale=time_scale)
        yield started
        started.close()

    @pytest.fixture(scope="module")
    def url(cell, tmp_path_factory):
        with station_server(cell, tmp_path_factory.mktemp("station") / "station.sqlite3", token, **app_options) as base_url:
            yield base_url

    return cell, url


@contextlib.contextmanager
def serve(app, port: int | None = None):
    """Run `app` under a real uvicorn server on 127.0.0.1:<free port>; yields the base URL."""
    port = port or free_port()
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", ws_per_message_deflate=False, lifespan="on")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 30
    with httpx.Client() as http:  # one client: httpx reads its CA bundle for each new one (45-160 ms of CPU)
        while True:
            try:
                if http.get(url + "/api/health", timeout=1.0).status_code == 200 and server.started:
                    break
            except httpx.HTTPError:
                pass
            if time.monotonic() > deadline or not thread.is_alive():
                server.should_exit = True
                raise RuntimeError("the test server did not start")
            time.sleep(0.05)
    try:
        yield url
    finally:
        server.should_exit = True
        thread.join(15)



@contextlib.contextmanager
def held_down(beat, pace_s: float = 0.03):
    """A held jog button: `beat` (a heartbeat over REST or the websocket) every pace_s on a thread of its own while
    the block runs. A test loop that waited between heartbeats let a late one end the jog on a busy machine (load
    17-26); a faster pace than the page's 30 ms queues re-plans behind each other on the server."""
    released = threading.Event()

    def run() -> None:
        while not released.is_set():
            beat()
            released.wait(pace_s)

    thread = threading.Thread(target=run, name="held-down", daemon=True)
    thread.start()
    try:
        yield
    finally:
        released.set()
        thread.join(30)

def wait_for(predicate, timeout_s: float = 10.0, poll_s: float = 0.05):
    """Poll until predicate() is truthy; returns its value, or raises AssertionError on timeout."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"condition not met within {timeout_s} s")
        time.sleep(poll_s)


def wait_sim(cell, duration_s: float, timeout_s: float = 30.0) -> None:
    """Wait until the simulation has advanced duration_s of simulated time: a condition on the sim clock
    (e.g. "the arm stayed still for 0.3 s"), not a fixed sleep of wall time."""
    start = cell.sim_time_s
    wait_for(lambda: cell.sim_time_s >= start + duration_s, timeout_s, 0.005)


def execute_plan_recorded(http: httpx.Client, cell, plan_id: str, headers: dict) -> tuple[httpx.Response, dict]:
    """POST /api/plans/{plan_id}/execute?wait=true with the simulated servos' reference recorded at every control
    tick meanwhile: (the answer, the trace: cell.stop_joint_recording())."""
    cell.start_joint_recording()
    try:
        done = http.post(f"/api/plans/{plan_id}/execute", params={"wait": "true"}, headers=headers)
    finally:
        trace = cell.stop_joint_recording()
    return done, trace
