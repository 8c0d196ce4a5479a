"""Reading recordings back with the `mcap` library, cut-short files included.

A finished recording has MCAP's summary (statistics, channel list); a recording cut short (SIGKILL, power loss)
ends inside the chunk being written and has no summary: its complete chunks are read in order up to the
damage (`truncated`). Messages decode with mcap-protobuf-support (Foxglove's schemas are protobuf) or as JSON.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_protobuf.decoder import DecoderFactory

from armlab.errors import InvalidInput


class DamagedRecording(InvalidInput):
    """Not an MCAP file, or damaged before its first complete chunk."""


@dataclass
class RecordingSummary:
    """What one MCAP file holds: per topic its schema name and message count, the first and last log times."""

    complete: bool  # MCAP's summary section is there (the recording was closed)
    truncated: bool  # the file ends inside a record (cut short): read up to there
    topics: dict[str, dict] = field(default_factory=dict)  # topic -> {"schema": name, "count": n}
    start_ns: int | None = None
    end_ns: int | None = None
    metadata: dict[str, dict] = field(default_factory=dict)

    @property
    def duration_s(self) -> float:
        return 0.0 if self.start_ns is None else (self.end_ns - self.start_ns) / 1e9

    @property
    def message_count(self) -> int:
        return sum(topic["count"] for topic in self.topics.values())


def _stream(path: Path, metadata: dict | None = None) -> Iterator[tuple[Schema | None, Channel, Message]]:
    """Every message of the file in file order; a cut-short tail raises _Truncated after the last good one.
    metadata: filled with the file's metadata records ({name: {key: value}}) as they are met."""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    with open(path, "rb") as stream:
        reader = StreamReader(stream, skip_magic=False, validate_crcs=True)
        try:
            for record in reader.records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata) and metadata is not None:
                    metadata[record.name] = dict(record.metadata)
                elif isinstance(record, Message):
                    channel = channels[record.channel_id]
                    yield schemas.get(channel.schema_id), channel, record
        except (McapError, EOFError, ValueError, KeyError) as error:
            raise _Truncated(str(error)) from error


class _Truncated(Exception):
    pass


def iter_messages(path: str | Path, topics: set[str] | None = None) -> Iterator[tuple[str, str, int, object]]:
    """(topic, schema name, log_time_ns, decoded message) in file order, up to the damage of a cut-short file.
    Protobuf messages decode to their classes, JSON to dicts."""
    decode = _Decoder()
    try:
        for schema, channel, message in _stream(Path(path)):
            if topics is None or channel.topic in topics:
                yield channel.topic, schema.name if schema else "", message.log_time, decode(schema, channel, message)
    except _Truncated:
        return


def summarize(path: str | Path) -> RecordingSummary:
    """The file's summary (from MCAP's summary section when it has one, else by reading it through)."""
    path = Path(path)
    try:
        with open(path, "rb") as stream:
            reader = make_reader(stream)
            summary = reader.get_summary()
            metadata = {record.name: dict(record.metadata) for record in reader.iter_metadata()}
    except (McapError, EOFError, ValueError, OSError):
        summary = None
    if summary is not None and summary.statistics is not None:
        stats = summary.statistics
        topics = {
            channel.topic: {"schema": summary.schemas[channel.schema_id].name if channel.schema_id in summary.schemas else "",
                            "count": int(stats.channel_message_counts.get(channel_id, 0))}
            for channel_id, channel in summary.channels.items()
        }
        start = stats.message_start_time if stats.message_count else None
        end = stats.message_end_time if stats.message_count else None
        return RecordingSummary(True, False, topics, start, end, metadata)
    return _scan(path)


MAGIC = b"\x89MCAP0\r\n"


def _scan(path: Path) -> RecordingSummary:
    result = RecordingSummary(complete=False, truncated=False)
    try:
        with open(path, "rb") as stream:
            if stream.read(len(MAGIC)) != MAGIC:
                raise DamagedRecording(f"{path.name} is not an MCAP recording (it does not start with MCAP's magic bytes)")
        for schema, channel, message in _stream(path, result.metadata):
            topic = result.topics.setdefault(channel.topic, {"schema": schema.name if schema else "", "count": 0})
            topic["count"] += 1
            result.start_ns = message.log_time if result.start_ns is None else min(result.start_ns, message.log_time)
            result.end_ns = message.log_time if result.end_ns is None else max(result.end_ns, message.log_time)
    except _Truncated:
        result.truncated = True
    except OSError as error:
        raise DamagedRecording(f"{path.name} cannot be read: {error}") from None
    return result


class _Decoder:
    def __init__(self) -> None:
        self._protobuf = DecoderFactory()
        self._cache: dict[int, object] = {}

    def __call__(self, schema: Schema | None, channel: Channel, message: Message) -> object:
        if channel.message_encoding == "json":
            return json.loads(message.data)
        decoder = self._cache.get(channel.schema_id)
        if decoder is None:
            decoder = self._cache[channel.schema_id] = self._protobuf.decoder_for(channel.message_encoding, schema)
        if decoder is None:
            return message.data
        return decoder(message.data)
