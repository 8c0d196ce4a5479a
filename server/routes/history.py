"""History: the station's event log as kept in its database (searchable by text, level and time range; exportable as
CSV or JSON), and past job runs with their scores and breakdowns. Absurd ranges (from after to, times past the year
2100, NaN) and limits above 5000 are refused with a 422 that says which."""

from __future__ import annotations

import csv
import io
import json
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Response
from starlette.concurrency import run_in_threadpool

from server.deps import StationDep

router = APIRouter(prefix="/api/history", tags=["history"])

Text = Annotated[str | None, Query(max_length=200, description="only rows whose message (or job name) contains this")]
Time = Annotated[float | None, Query(description="seconds since 1970 (time.time()); from_s <= to_s")]
Limit = Annotated[int, Query(description="the most rows, 1-5000")]
Format = Annotated[Literal["json", "csv"], Query(description="json, or csv (a download)")]
EVENT_COLUMNS = ("time_s", "level", "kind", "message")
JOB_COLUMNS = ("id", "name", "state", "started_s", "finished_s", "points", "max_points", "message", "score", "result")


def _answer(rows: list[dict], columns: tuple[str, ...], format: str, download: bool, stem: str) -> Response:
    if format == "csv":
        buffer = io.StringIO()
        writer = csv.writer(buffer)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([json.dumps(row.get(c)) if isinstance(row.get(c), (dict, list)) else row.get(c, "") for c in columns])
        return Response(buffer.getvalue(), media_type="text/csv",
                        headers={"Content-Disposition": f'attachment; filename="{stem}.csv"'})
    headers = {"Content-Disposition": f'attachment; filename="{stem}.json"'} if download else {}
    return Response(json.dumps({"data": rows, "count": len(rows)}), media_type="application/json", headers=headers)


DOWNLOAD = {200: {"content": {"application/json": {}, "text/csv": {}}, "description": "the rows (JSON), or a CSV download"}}


@router.get("/events", responses=DOWNLOAD)
async def read_events(station: StationDep, text: Text = None, level: Literal["info", "warn", "error"] | None = None,
                      from_s: Time = None, to_s: Time = None, limit: Limit = 200, format: Format = "json",
                      download: bool = False) -> Response:
    """The kept event log, newest first: {data: [{id, time_s, level, kind, message}], count} or CSV."""
    await run_in_threadpool(station.event_history.flush)
    rows = await run_in_threadpool(station.store.search_events, text, level, from_s, to_s, limit)
    return _answer(rows, EVENT_COLUMNS, format, download, "armlab-events")


@router.get("/jobs", responses=DOWNLOAD)
async def read_jobs(station: StationDep, text: Text = None,
                    state: Literal["running", "succeeded", "failed", "cancelled", "interrupted"] | None = None,
                    from_s: Time = None, to_s: Time = None, limit: Limit = 200, format: Format = "json",
                    download: bool = False) -> Response:
    """Past job runs started in the range, newest first, each with its result: the score and its breakdown for a
    simulated run ({data: [{id, name, state, message, started_s, finished_s, points, max_points, score: {.., breakdown},
    result}], count} or CSV)."""
    rows = await run_in_threadpool(station.store.search_jobs, text, state, from_s, to_s, limit)
    for row in rows:
        score = row.get("score") if isinstance(row.get("score"), dict) else {}
        row["points"], row["max_points"] = score.get("points"), score.get("max_points")
    return _answer(rows, JOB_COLUMNS, format, download, "armlab-jobs")
