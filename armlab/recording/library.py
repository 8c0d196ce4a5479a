"""The recordings folder: start and stop the one recording at a time, list, find, delete, and keep the disk budget.

Files: <id>.mcap and, once a recording has ended, <id>.json (its summary). An .mcap without a summary (the station
was killed while recording) is read through once (reader.py: up to its last complete chunk), listed as `truncated`,
and its summary written. The budget (recording.budget_mb) covers every recording: starting one, and each flush of
the running one, deletes the oldest ended recordings until the folder fits; the running one is never deleted, and
when it alone no longer fits it stops (kept).
"""

from __future__ import annotations

import json
import logging
import re
import secrets
import threading
import time
from pathlib import Path
from typing import Any

from armlab.errors import RefusedByCheck
from armlab.recording.reader import DamagedRecording, summarize
from armlab.recording.recorder import MB, Recording, fsync_dir, write_json_atomically
from armlab.station.config import RecordingConfig
from armlab.store import NotFound

log = logging.getLogger(__name__)

ID_PATTERN = re.compile(r"^\d{8}T\d{6}Z-[0-9a-f]{6}$")
MAX_LABEL_CHARS = 200


class AlreadyRecording(RefusedByCheck):
    """A recording is running: one at a time (HTTP 409); the running one goes on untouched."""


class NotRecording(RefusedByCheck):
    """Stop asked while nothing is recording (HTTP 409)."""


class RecordingBusy(RefusedByCheck):
    """The recording asked for is still being written (HTTP 409): stop it first."""


class DiskFull(RefusedByCheck):
    """Too little free disk for a new recording (HTTP 507); nothing already recorded is touched."""


def new_id() -> str:
    return time.strftime("%Y%m%dT%H%M%SZ", time.gmtime()) + "-" + secrets.token_hex(3)


class RecordingLibrary:
    """The recordings of one station in `directory` (created on first use)."""

    def __init__(self, directory: str | Path, config: RecordingConfig | None = None) -> None:
        self.directory = Path(directory)
        self.config = config or RecordingConfig()
        self._lock = threading.Lock()  # guards _active; no file I/O under it
        self._active: Recording | None = None

    # Recording --------------------------------------------------------------------------------------

    def start(self, station: Any, label: str = "", source: str | None = None) -> dict:
        """Start recording `station`; AlreadyRecording while one runs, DiskFull below min_free_mb free."""
        label = (label or "").strip()[:MAX_LABEL_CHARS]
        self.directory.mkdir(parents=True, exist_ok=True)
        with self._lock:
            if self._active is not None and self._active.running:
                raise AlreadyRecording(f"already recording ({self._active.id}, {self._active.duration_s:.0f} s): stop it first; "
                                       "it goes on untouched")
            recording = Recording(station, self.directory / f"{new_id()}.mcap", self.config, label=label, source=source,
                                  over_budget=self._over_budget, on_end=self._ended)
            self._active = recording  # claimed before the file is opened: a second start is refused meanwhile
        try:
            self.enforce_budget()
            problem = recording._disk_problem()
            if problem is not None:
                raise DiskFull(f"cannot start a recording: {problem}; delete recordings or free disk space")
            recording.start()
        except BaseException:
            with self._lock:
                if self._active is recording:
                    self._active = None
            raise
        fsync_dir(self.directory)
        station.events.add("info", f"recording {recording.id} started" + (f" ({label})" if label else ""))
        return recording.info()

    def stop(self) -> dict:
        with self._lock:
            recording = self._active
        if recording is None or not recording.running:
            raise NotRecording("nothing is recording")
        return recording.stop("stopped")

    def close(self) -> None:
        """Stop the running recording, if any (the station is shutting down)."""
        with self._lock:
            recording = self._active
        if recording is not None and recording.running:
            recording.stop("the station stopped")

    def active(self) -> dict | None:
        with self._lock:
            recording = self._active
        return recording.info() if recording is not None and recording.running else None

    def _ended(self, recording: Recording) -> None:
        with self._lock:
            if self._active is recording:
                self._active = None

    # The folder -------------------------------------------------------------------------------------

    def path(self, recording_id: str) -> Path:
        """The .mcap of `recording_id`; NotFound for an unknown or malformed id."""
        if not isinstance(recording_id, str) or not ID_PATTERN.match(recording_id):
            raise NotFound(f"no recording '{recording_id}' (ids look like 20261203T100000Z-a1b2c3)")
        path = self.directory / f"{recording_id}.mcap"
        if not path.is_file():
            raise NotFound(f"no recording '{recording_id}'")
        return path

    def info(self, recording_id: str) -> dict:
        path = self.path(recording_id)
        active = self._running(recording_id)
        return active.info() if active is not None else self._ended_info(path)

    def list(self) -> list[dict]:
        """Every recording, newest first (the running one included)."""
        if not self.directory.is_dir():
            return []
        infos = []
        for path in sorted(self.directory.glob("*.mcap"), reverse=True):
            if not ID_PATTERN.match(path.stem):
                continue
            active = self._running(path.stem)
            infos.append(active.info() if active is not None else self._ended_info(path))
        return infos

    def delete(self, recording_id: str) -> None:
        path = self.path(recording_id)
        if self._running(recording_id) is not None:
            raise RecordingBusy(f"recording {recording_id} is still being written: stop it first")
        self._remove(path)

    def _running(self, recording_id: str) -> Recording | None:
        with self._lock:
            recording = self._active
        return recording if recording is not None and recording.id == recording_id and recording.running else None

    def _ended_info(self, path: Path) -> dict:
        """An ended recording's summary: its sidecar, else read from the MCAP (and the sidecar written)."""
        sidecar = path.with_suffix(".json")
        size = path.stat().st_size if path.exists() else 0
        try:
            info = json.loads(sidecar.read_text())
            if info.get("size_bytes") == size:
                return info
        except (OSError, ValueError):
            info = {}
        try:
            summary = summarize(path)
        except DamagedRecording as error:
            return {**self._blank(path, size), "state": "damaged", "stop_reason": str(error)}
        truncated = not summary.complete
        info = {
            **self._blank(path, size), **{k: v for k, v in info.items() if k in ("label", "source", "jobs", "states", "started_utc") and v},
            "duration_s": round(summary.duration_s, 3), "complete": summary.complete, "truncated": truncated,
            "stop_reason": info.get("stop_reason") or ("cut short (the station stopped while recording): readable up to its last "
                                                       "complete chunk" if truncated else None),
            "topics": {topic: data["count"] for topic, data in summary.topics.items() if data["count"]},
        }
        meta = summary.metadata.get("armlab", {})
        info["label"] = info.get("label") or meta.get("label", "")
        try:
            write_json_atomically(sidecar, info)
        except OSError as error:
            log.warning("cannot write %s: %s", sidecar, error)
        return info

    @staticmethod
    def _blank(path: Path, size: int) -> dict:
        stem = path.stem
        started = f"{stem[0:4]}-{stem[4:6]}-{stem[6:8]}T{stem[9:11]}:{stem[11:13]}:{stem[13:15]}Z"
        return {"id": stem, "label": "", "source": None, "started_utc": started, "state": "finished", "stop_reason": None,
                "duration_s": 0.0, "size_bytes": size, "complete": False, "truncated": False, "topics": {}, "jobs": [], "states": [],
                "sampler_error": None}

    def _remove(self, path: Path) -> None:
        for file in (path, path.with_suffix(".json")):
            file.unlink(missing_ok=True)
        fsync_dir(self.directory)

    # The budget -------------------------------------------------------------------------------------

    def enforce_budget(self, running_bytes: int = 0) -> list[str]:
        """Delete the oldest ended recordings until every recording fits recording.budget_mb (the running one is
        counted, never deleted). Returns the ids deleted."""
        budget = self.config.budget_mb * MB
        with self._lock:
            running = self._active.id if self._active is not None else None
        ended = sorted(path for path in self.directory.glob("*.mcap") if ID_PATTERN.match(path.stem) and path.stem != running)
        total = running_bytes + sum(path.stat().st_size for path in ended)
        deleted = []
        for path in ended:  # oldest first: the ids start with the UTC start time
            if total <= budget:
                break
            total -= path.stat().st_size
            self._remove(path)
            deleted.append(path.stem)
        if deleted:
            log.info("recording budget %g MB: deleted the oldest recordings %s", self.config.budget_mb, ", ".join(deleted))
        return deleted

    def _over_budget(self, running_bytes: int) -> str | None:
        """At each flush of the running recording: make room; a reason when it alone is over the budget."""
        self.enforce_budget(running_bytes)
        if running_bytes > self.config.budget_mb * MB:
            return f"budget reached: the recording alone is over recording.budget_mb {self.config.budget_mb:g} MB"
        return None
