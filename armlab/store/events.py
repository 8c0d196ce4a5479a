"""The station's event log on disk: every operator event (level, kind, message, wall time), kept across page reloads
and restarts, searched by text, level and time range (newest first), and the job history searched alike."""

from __future__ import annotations

import json
import math
from collections.abc import Iterable

from armlab.errors import InvalidInput
from armlab.store.database import ROW_ERRORS, Database

MAX_ROWS = 5000  # the most rows one search returns
LATEST_TIME_S = 4102444800.0  # 2100-01-01: later times are refused (an absurd range)
LEVELS = ("info", "warn", "error")


def checked_range(from_s: float | None, to_s: float | None, limit: int) -> tuple[float, float, int]:
    """A search range: finite times from 0 to LATEST_TIME_S, from <= to, 1 <= limit <= MAX_ROWS (InvalidInput why)."""
    bounds = []
    for name, value, default in (("from_s", from_s, 0.0), ("to_s", to_s, LATEST_TIME_S)):
        value = default if value is None else value
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InvalidInput(f"{name} must be a finite time (seconds since 1970), got {value!r}")
        if not 0.0 <= value <= LATEST_TIME_S:
            raise InvalidInput(f"{name} must be from 0 to {LATEST_TIME_S:.0f} (the year 2100), got {value!r}")
        bounds.append(float(value))
    if bounds[0] > bounds[1]:
        raise InvalidInput(f"from_s ({bounds[0]:.3f}) is after to_s ({bounds[1]:.3f}): give the earlier time first")
    if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= MAX_ROWS:
        raise InvalidInput(f"limit must be an integer from 1 to {MAX_ROWS}, got {limit!r}")
    return bounds[0], bounds[1], limit


def _like(text: str | None) -> str:
    escaped = (text or "").replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_")
    return f"%{escaped}%"


class EventTables(Database):
    """The events table, and the searches of events and job results."""

    def add_events(self, events: Iterable[dict]) -> int:
        """Store events ({"level", "kind", "message", "time_s"}) in one transaction; returns how many."""
        rows = [(float(e["time_s"]), str(e["level"]), str(e.get("kind", "general")), str(e["message"])) for e in events]
        if not rows:
            return 0
        connection = self._connect()
        try:
            with connection:
                connection.executemany("INSERT INTO events (time_s, level, kind, message) VALUES (?, ?, ?, ?)", rows)
        finally:
            connection.close()
        return len(rows)

    def search_events(self, text: str | None = None, level: str | None = None, from_s: float | None = None,
                      to_s: float | None = None, limit: int = 200) -> list[dict]:
        """Events whose message contains `text` (case-insensitive), of `level`, with from_s <= time_s <= to_s,
        newest first, at most `limit` (InvalidInput for an absurd range or an unknown level)."""
        start, end, limit = checked_range(from_s, to_s, limit)
        if level is not None and level not in LEVELS:
            raise InvalidInput(f"level must be one of {LEVELS}, got {level!r}")
        rows = self._run(
            "SELECT id, time_s, level, kind, message FROM events WHERE time_s BETWEEN ? AND ? AND (? IS NULL OR level = ?) "
            "AND message LIKE ? ESCAPE '\\' ORDER BY time_s DESC, id DESC LIMIT ?",
            (start, end, level, level, _like(text), limit),
        )
        return [{"id": r[0], "time_s": r[1], "level": r[2], "kind": r[3], "message": r[4]} for r in rows]

    def search_jobs(self, text: str | None = None, state: str | None = None, from_s: float | None = None,
                    to_s: float | None = None, limit: int = 200) -> list[dict]:
        """Job results started in [from_s, to_s] whose name or message contains `text`, in `state`, newest first,
        each with its result and, for a scored run, its score with the breakdown; damaged rows are logged and skipped."""
        start, end, limit = checked_range(from_s, to_s, limit)
        rows = self._run(
            "SELECT id, name, state, message, started_s, finished_s, result_json, score_json FROM job_results WHERE started_s BETWEEN ? AND ? "
            "AND (? IS NULL OR state = ?) AND (name LIKE ? ESCAPE '\\' OR message LIKE ? ESCAPE '\\') ORDER BY started_s DESC LIMIT ?",
            (start, end, state, state, _like(text), _like(text), limit),
            raw_text=True,
        )
        results = []
        for row in rows:
            try:
                text_row = [value.decode("utf-8") if isinstance(value, bytes) else value for value in row]
                results.append({
                    "id": text_row[0], "name": text_row[1], "state": text_row[2], "message": text_row[3],
                    "started_s": float(text_row[4]), "finished_s": None if text_row[5] is None else float(text_row[5]),
                    "result": json.loads(text_row[6]) if text_row[6] else None,
                    "score": json.loads(text_row[7]) if text_row[7] else None,
                })
            except ROW_ERRORS as error:
                self._skip(f"job result {row[0]!r}", error)
        return results

    def record_job_score(self, job_id: str, score: dict | None) -> None:
        """Keep a finished job's score (points, max_points, breakdown) with its row."""
        self._run("UPDATE job_results SET score_json = ? WHERE id = ?", (json.dumps(score, default=str), job_id))
