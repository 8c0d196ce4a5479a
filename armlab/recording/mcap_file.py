"""An MCAP file written with the `mcap` library: the messages encoded by foxglove-sdk (its schemas, protobuf), the
chunks compressed by python-zstandard and written by Python's file object, both with the GIL released.

Why not foxglove-sdk's own MCAP writer: it holds the GIL while it compresses and writes a chunk (measured: a 1.8 MB
depth frame's chunk held every other Python thread of the station for ~15 ms, up to 40 ms), and the station's
threads (the e-stop's included) must never wait on a recording. Thread-safe: a lock serialises the recorder's two
threads (a chunk being compressed makes the other recorder thread wait, never the station's).
"""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path
from typing import Any

from mcap.writer import CompressionType, Writer

import armlab


class McapFile:
    """One MCAP file at `path` (which must not exist), chunks of about chunk_size_bytes (zstd)."""

    def __init__(self, path: str | Path, chunk_size_bytes: int) -> None:
        self.path = Path(path)
        self._file = open(self.path, "xb")  # noqa: SIM115 - closed by close()
        self._lock = threading.Lock()
        self._writer = Writer(self._file, chunk_size=chunk_size_bytes, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library=f"armlab {armlab.__version__}")
        self._schemas: dict[tuple[str, str], int] = {}
        self._closed = False

    def channel(self, topic: str, schema: Any) -> McapChannel:
        """A channel for foxglove-sdk messages of `schema` (a message class: its get_schema(), protobuf) or, given a
        dict, a JSON-schema channel of dicts."""
        if isinstance(schema, dict):
            name, encoding, data, message_encoding = schema.get("title", topic), "jsonschema", json.dumps(schema).encode(), "json"
        else:
            described = schema.get_schema()
            name, encoding, data, message_encoding = described.name, described.encoding, bytes(described.data), described.encoding
        with self._lock:
            schema_id = self._schemas.get((name, encoding))
            if schema_id is None:
                schema_id = self._schemas[(name, encoding)] = self._writer.register_schema(name, encoding, data)
            channel_id = self._writer.register_channel(topic, message_encoding, schema_id)
        return McapChannel(self, channel_id, message_encoding == "json")

    def write(self, channel_id: int, data: bytes, log_time_ns: int, publish_time_ns: int) -> None:
        with self._lock:
            if not self._closed:
                self._writer.add_message(channel_id, log_time_ns, data, publish_time_ns)

    def write_metadata(self, name: str, data: dict[str, str]) -> None:
        with self._lock:
            self._writer.add_metadata(name, data)

    def flush(self) -> None:
        """Close the chunk being filled and hand the bytes to the OS (a SIGKILL then loses nothing written before)."""
        with self._lock:
            if not self._closed:
                self._writer.flush()
                self._file.flush()

    def close(self) -> None:
        """Write MCAP's summary and close the file (fsync'd: a power cut keeps it)."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            try:
                self._writer.finish()
                self._file.flush()
                os.fsync(self._file.fileno())
            finally:
                self._file.close()


class McapChannel:
    """What StationChannels logs to: log(message, log_time) like a foxglove channel; publish time = log time."""

    def __init__(self, file: McapFile, channel_id: int, is_json: bool) -> None:
        self._file, self.id, self._json = file, channel_id, is_json

    def log(self, message: Any, log_time: int) -> None:
        data = json.dumps(message).encode() if self._json else message.encode()
        self._file.write(self.id, data, int(log_time), int(log_time))

    def close(self) -> None:
        """Nothing to release (the file closes once for all its channels)."""
