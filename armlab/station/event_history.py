"""The event log kept on disk: every event the station's EventLog takes is written to the database by one small writer
thread (never by the thread that raised it, which may hold the station's lock), so the History panel finds it after a
page reload or a restart. `flush()` waits until what was logged so far is on disk (searches and close call it)."""

from __future__ import annotations

import logging
import queue
import threading
from typing import Any

log = logging.getLogger(__name__)

FLUSH_TIMEOUT_S = 5.0
_STOP = object()  # the writer's last item (close)


class EventHistory:
    """Writes each event of `events` (a station EventLog) to `store` (add_events) in the background."""

    def __init__(self, events: Any, store: Any) -> None:
        self._store = store
        self._queue: queue.Queue[dict] = queue.Queue()
        self._thread: threading.Thread | None = None
        self._start_lock = threading.Lock()
        self._failures = 0
        self._closed = False
        events.add_listener(self._on_event)

    def _on_event(self, event: dict) -> None:
        if self._closed:
            return  # the station closed: its writer has ended (close wrote everything logged before)
        self._queue.put(dict(event))
        if self._thread is None:
            with self._start_lock:
                if self._thread is None and not self._closed:
                    self._thread = threading.Thread(target=self._write_loop, name="event-history", daemon=True)
                    self._thread.start()

    def _write_loop(self) -> None:
        stopping = False
        while not stopping:
            batch = [self._queue.get()]
            while batch[-1] is not _STOP:
                try:
                    batch.append(self._queue.get_nowait())
                except queue.Empty:
                    break
            if batch[-1] is _STOP:
                stopping = True
                batch.pop()
                self._queue.task_done()
            if not batch:
                continue
            try:
                self._store.add_events(batch)
            except Exception as error:  # noqa: BLE001 - the log must not take the station down; said once per failure run
                self._failures += 1
                if self._failures == 1:
                    log.warning("event history: %d event(s) not written to the database: %s", len(batch), error)
            else:
                self._failures = 0
            for _ in batch:
                self._queue.task_done()

    def close(self, timeout_s: float = FLUSH_TIMEOUT_S) -> bool:
        """Write what was logged so far and end the writer (True when it ended within timeout_s); later events
        are not kept."""
        with self._start_lock:
            self._closed = True
            thread = self._thread
        if thread is None:
            return True
        self._queue.put(_STOP)
        thread.join(timeout_s)
        return not thread.is_alive()

    def flush(self, timeout_s: float = FLUSH_TIMEOUT_S) -> bool:
        """Wait until every event logged so far is written (True), or timeout_s passed (False)."""
        done = threading.Event()

        def wait() -> None:
            self._queue.join()
            done.set()

        threading.Thread(target=wait, name="event-history-flush", daemon=True).start()
        return done.wait(timeout_s)
