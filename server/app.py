"""create_app(): the FastAPI application factory. No module-level app or state."""

from __future__ import annotations

from fastapi import FastAPI

import armlab


def create_app() -> FastAPI:
    app = FastAPI(title="ArmLab Control Station", version=armlab.__version__)

    @app.get("/api/health", tags=["station"])
    def read_health() -> dict:
        """Liveness check."""
        return {"status": "ok", "version": armlab.__version__}

    return app
