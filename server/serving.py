"""Running the app under uvicorn with a prompt, bounded shutdown.

On Ctrl-C or SIGTERM the station is halted and its job cancelled at once (in the signal handler, before
uvicorn starts waiting for open requests), so `?wait=true` requests and running jobs end within a
second; uvicorn then waits at most GRACEFUL_S for connections before the lifespan closes the station,
which joins its threads (bounded) and reports them.
"""

from __future__ import annotations

import logging

import uvicorn

log = logging.getLogger(__name__)

GRACEFUL_S = 1  # uvicorn's wait for open connections after a signal (whole seconds)


class StationServer(uvicorn.Server):
    """uvicorn.Server whose signal handler first halts the station (app.state.station)."""

    def __init__(self, config: uvicorn.Config, app) -> None:
        super().__init__(config)
        self._app = app

    def handle_exit(self, sig, frame) -> None:
        station = getattr(self._app.state, "station", None)
        if station is not None and not self.should_exit:
            try:
                station.begin_shutdown()
            except Exception:  # noqa: BLE001 - shutting down matters more than a failed halt
                log.exception("halting the station at shutdown failed")
        super().handle_exit(sig, frame)


def run(app, host: str, port: int, log_level: str, log_config: dict | None = None) -> None:
    """Serve `app` until a signal; bounded shutdown (see the module docstring)."""
    config = uvicorn.Config(
        app, host=host, port=port, log_level=log_level, ws_per_message_deflate=False, log_config=log_config,
        timeout_graceful_shutdown=GRACEFUL_S,
    )
    try:
        StationServer(config, app).run()
    except KeyboardInterrupt:  # uvicorn re-raises a Ctrl-C after its shutdown: the station is closed by then
        pass
