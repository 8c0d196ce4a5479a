"""create_app(): the FastAPI application factory. No module-level app or state.

The station comes from `station_factory()` (default: the real-time simulation), started in the
lifespan and closed at shutdown; the routes are thin calls into it. web/ is served at /.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles

import armlab
from armlab.recording import RecordingLibrary
from armlab.station import load_station_config
from armlab.station.factory import make_sim_station
from server.auth import resolve_token
from server.errors import install_error_handlers
from server.guard import HostOriginGuard
from server.routes import (
    arm,
    auto,
    board,
    calibration,
    calibration_settings,
    colors,
    detections,
    history,
    intrinsics,
    jobs,
    plans,
    programs,
    recordings,
    repeat,
    sim,
    speed,
    station,
    stream,
    view3d,
)
from server.stream import StreamHub
from server.waiting import Waiter

log = logging.getLogger(__name__)

WEB_DIR = Path(__file__).resolve().parents[1] / "web"


def default_station_factory():
    """The simulated workcell with the station of config/station.yaml."""
    return make_sim_station(load_station_config())


SAFETY_THREADS = 4  # the e-stop's own pool: it never queues behind blocked `?wait=true` requests
STATUS_THREADS = 4  # status and reset: never queued behind commands that hold the worker threads (planning, sends)


def _open_station(factory: Callable[[], Any]):
    """(station, closer): a factory may return a Station or a handle with .station and .close()."""
    made = factory()
    station = getattr(made, "station", made)
    return station, made.close


def create_app(
    station_factory: Callable[[], Any] | None = None,
    token: str | None = None,
    web_dir: str | Path | None = WEB_DIR,
    allowed_hosts: Iterable[str] = (),
    on_close: Callable[[dict], None] | None = None,
    recordings_dir: str | Path | None = None,
    live: Any = None,
) -> FastAPI:
    """The app. token: the control token (default: $ARMLAB_TOKEN, else generated: read app.state.token).

    allowed_hosts: Host names served besides the loopback names (the --host name, config allowed_hosts);
    any other Host, and any foreign Origin, gets 403 (server/guard.py).
    on_close(report): called at shutdown with the station's close report ({"joined", "alive"} thread names).
    recordings_dir: where MCAP recordings go (default: the config's recording.directory, else recordings/ next to
    the station's database).
    live: a started armlab.recording.live.LiveServer (`armlab serve --foxglove`): each station the app opens is
    streamed to it while the app runs (the caller stops it).
    """
    factory = station_factory or default_station_factory

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        station_obj, close = _open_station(factory)
        app.state.station = station_obj
        app.state.safety_pool = ThreadPoolExecutor(SAFETY_THREADS, thread_name_prefix="armlab-safety")
        app.state.status_pool = ThreadPoolExecutor(STATUS_THREADS, thread_name_prefix="armlab-status")
        app.state.hub = StreamHub(station_obj, station_obj.config.jpeg_quality, app.state.safety_pool)
        app.state.hub.start()
        app.state.waiter = Waiter(station_obj)  # `?wait=true` requests wait here, not on worker threads
        app.state.waiter.start()
        store_path = getattr(station_obj.store, "path", None)
        app.state.recordings = RecordingLibrary(recordings_dir or station_obj.config.recordings_dir(store_path), station_obj.config.recording)
        app.state.live = live
        if live is not None:
            live.attach(station_obj)
        try:
            yield
        finally:
            station_obj.begin_shutdown()  # halt and end the job first: waiting requests return at once
            app.state.recordings.close()  # the halt is in it; the file closed complete
            if live is not None:
                live.detach()
            app.state.waiter.stop()
            app.state.hub.stop()
            app.state.station = None
            report = close() or {}
            app.state.safety_pool.shutdown(wait=False, cancel_futures=True)
            app.state.status_pool.shutdown(wait=False, cancel_futures=True)
            app.state.close_report = report
            if report.get("alive"):
                log.warning("shutdown: threads still running: %s", ", ".join(report["alive"]))
            if on_close is not None:
                on_close(report)

    app = FastAPI(
        title="ArmLab Control Station",
        version=armlab.__version__,
        lifespan=lifespan,
        description="REST API of the ArmLab control station. SI units; mutating calls need 'Authorization: Bearer <token>'.",
    )
    app.state.token = resolve_token(token)[0]
    app.state.station = None
    install_error_handlers(app)
    app.add_middleware(HostOriginGuard, allowed_hosts=tuple(allowed_hosts))

    @app.get("/api/health", tags=["station"])
    def read_health() -> dict:
        """Liveness check."""
        return {"status": "ok", "version": armlab.__version__}

    for module in (station, arm, board, calibration, calibration_settings, colors, intrinsics, detections, history, jobs, auto, plans, programs, recordings,
                   repeat, sim, speed, stream, view3d):
        app.include_router(module.router)
    if web_dir is not None and Path(web_dir, "index.html").exists():
        app.mount("/", StaticFiles(directory=str(web_dir), html=True), name="web")
    return app
