"""One MCAP recording of a station: an McapFile (messages in foxglove-sdk's schemas; chunks compressed and written
with the GIL released) fed by a StationSampler.

Encoding and writing run on the sampler's threads, never on the station's threads or under its lock.
Chunks are zstd-compressed and closed at least every flush_interval_s, so a recording cut by SIGKILL is readable up
to its last closed chunk. Every flush also checks the disk: below min_free_mb free, or over its share of the budget,
the recording stops by itself and closes the file (what was recorded stays, readable to the end); its `stop_reason`
says why. A sidecar <id>.json holds the summary once the recording has ended (library.py lists from it).
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import armlab
from armlab.recording.channels import StationChannels
from armlab.recording.mcap_file import McapFile
from armlab.recording.reader import DamagedRecording, summarize
from armlab.recording.sampler import StationSampler
from armlab.station.config import RecordingConfig

log = logging.getLogger(__name__)

MB = 1_000_000
CLOSE_WAIT_S = 15.0  # a stop that finds another one closing the file waits this long for it


def write_json_atomically(path: Path, data: dict) -> None:
    partial = path.with_name(path.name + ".partial")
    partial.write_text(json.dumps(data, indent=1) + "\n")
    partial.replace(path)


class Recording:
    """One recording to `path` (an .mcap that must not exist). start(), then stop(reason) (or it stops itself: disk).

    over_budget(size_bytes) -> str | None: asked at every flush; a reason stops the recording (the library's budget).
    on_end(recording): called once when it has ended, from whichever thread ended it."""

    def __init__(self, station: Any, path: Path, config: RecordingConfig, *, label: str = "", source: str | None = None,
                 over_budget: Callable[[int], str | None] | None = None,
                 on_end: Callable[[Recording], None] | None = None) -> None:
        self.station, self.path, self.config = station, Path(path), config
        self.id = self.path.stem
        self.label, self.source = label, source
        self.over_budget, self.on_end = over_budget, on_end
        self.started_utc = ""
        self.started_ns = 0
        self.ended_ns: int | None = None
        self.stop_reason: str | None = None
        self._end_lock = threading.Lock()
        self._ended = threading.Event()  # stopping or stopped
        self._closed = threading.Event()  # stopped: the file closed and its sidecar written
        self._writer: McapFile | None = None
        self._channels: StationChannels | None = None
        self._sampler: StationSampler | None = None
        self._next_flush_s = 0.0
        self._written: Any = None  # the file's RecordingSummary once it has ended

    def start(self) -> None:
        self.started_ns = time.time_ns()
        self.started_utc = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(self.started_ns / 1e9))
        self._writer = McapFile(self.path, self.config.chunk_size_kb * 1024)
        try:
            self._channels = StationChannels.on_file(self._writer)
            self._writer.write_metadata("armlab", {
                "id": self.id, "label": self.label, "source": self.source or "", "started_utc": self.started_utc,
                "backend": str(getattr(self.station, "backend", "")), "armlab_version": armlab.__version__,
                "workcell": str(getattr(self.station.config, "workcell", "")),
                "joint_names": ",".join(self.station.model.joint_names) if self.station.has_arm else "",
            })
            self._writer.flush()  # the header, the metadata and the channels are on disk before the first sample
            self._next_flush_s = time.monotonic() + self.config.flush_interval_s
            self._sampler = StationSampler(self.station, self._channels, self.config, housekeeping=self._housekeeping,
                                           on_failure=lambda reason: self.stop(reason, problem=True), batch_joints=True)
            self._sampler.start()
        except BaseException:
            self._writer.close()
            raise

    @property
    def running(self) -> bool:
        """Started and not yet closed (a recording being stopped still runs until its file is closed)."""
        return self._writer is not None and not self._closed.is_set()

    @property
    def size_bytes(self) -> int:
        try:
            return self.path.stat().st_size
        except OSError:
            return 0

    @property
    def duration_s(self) -> float:
        end_ns = self.ended_ns if self.ended_ns is not None else time.time_ns()
        return max(0.0, (end_ns - self.started_ns) / 1e9) if self.started_ns else 0.0

    def _housekeeping(self) -> None:
        """On the sample loop: close a chunk every flush_interval_s, then check the disk and the budget."""
        now_s = time.monotonic()
        if now_s < self._next_flush_s or self._ended.is_set():
            return
        self._next_flush_s = now_s + self.config.flush_interval_s
        self._writer.flush()
        reason = self._disk_problem()
        if reason is None and self.over_budget is not None:
            reason = self.over_budget(self.size_bytes)
        if reason is not None:
            self.stop(reason, problem=True)

    def _disk_problem(self) -> str | None:
        try:
            free_mb = shutil.disk_usage(self.path.parent).free / MB
        except OSError as error:
            return f"the recordings folder cannot be read: {error}"
        if free_mb < self.config.min_free_mb:
            return f"disk full: {free_mb:.0f} MB free, less than recording.min_free_mb {self.config.min_free_mb:g} MB"
        return None

    def stop(self, reason: str = "stopped", problem: bool = False) -> dict:
        """End the recording (idempotent; from any thread, the sampler's own included): stop sampling, close the
        file (summary written), write the sidecar. Returns info(). problem: it stops on its own (disk, budget): an
        error event, not an info."""
        with self._end_lock:
            stopping = self._ended.is_set()
            if not stopping and self._writer is not None:
                self.stop_reason = reason
                self._ended.set()
        if stopping or self._writer is None:
            if stopping and threading.current_thread() not in self._sampler_threads():
                self._closed.wait(CLOSE_WAIT_S)  # another thread is closing it: answer once it is closed
            return self.info()
        sampler = self._sampler
        try:
            if sampler is not None:
                sampler.stop()
                sampler.log_events(time.time_ns())  # what happened since the last tick, the stop's cause included
            if self._channels is not None:
                self._channels.close()
            self._writer.close()
        except Exception as error:  # noqa: BLE001 - the file keeps what it has; say why it is short
            log.warning("recording %s: closing the file failed: %s", self.id, error)
            self.stop_reason = f"{reason}; closing the file failed: {error}"
        self.ended_ns = time.time_ns()
        try:  # what the file holds (the summary just written), not what was handed to the writer
            self._written = summarize(self.path)
        except DamagedRecording as error:
            log.warning("recording %s: cannot read it back: %s", self.id, error)
        level = "error" if problem or self.stop_reason != reason else "info"
        self.station.events.add(level, f"recording {self.id} ended ({self.stop_reason}): {self.duration_s:.1f} s, "
                                       f"{self.size_bytes / MB:.1f} MB")
        info = {**self.info(), "state": "finished", "complete": bool(self._written is not None and self._written.complete)}
        try:
            write_json_atomically(self.path.with_suffix(".json"), info)
        except OSError as error:  # a full disk: the listing reads the MCAP itself
            log.warning("recording %s: cannot write its summary: %s", self.id, error)
        self._closed.set()
        if self.on_end is not None:
            self.on_end(self)
        return self.info()

    def _sampler_threads(self) -> list[threading.Thread]:
        return list(self._sampler._threads) if self._sampler is not None else []

    def info(self) -> dict:
        sampler, written = self._sampler, self._written
        if written is not None:
            counts = {topic: data["count"] for topic, data in written.topics.items() if data["count"]}
        else:
            counts = {topic: count for topic, count in (sampler.counts if sampler else {}).items() if count}
        return {
            "id": self.id, "label": self.label, "source": self.source, "started_utc": self.started_utc,
            "state": "recording" if self.running else "finished", "stop_reason": self.stop_reason,
            "duration_s": round(self.duration_s, 3), "size_bytes": self.size_bytes,
            "complete": bool(written is not None and written.complete),
            "truncated": bool(written is not None and not written.complete), "topics": counts, "jobs": list(sampler.jobs) if sampler else [],
            "states": list(sampler.states) if sampler else [],
            "sampler_error": sampler.error if sampler else None,
        }


def fsync_dir(path: Path) -> None:
    """Make a new or deleted name in `path` durable (POSIX)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
