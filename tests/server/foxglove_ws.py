"""A minimal Foxglove WebSocket client (the `websockets` package), speaking the protocol as the Foxglove app does:
serverInfo and advertise (JSON), subscribe, binary message data (opcode 1: subscription id u32, log time u64,
payload), fetchAsset and its binary response (opcode 4: request id u32, status u8, error length u32, error, data).
Protobuf payloads decode through the schema the server advertised (a FileDescriptorSet), JSON ones with json.

foxglove-sdk 0.30's server negotiates the "foxglove.sdk.v1" subprotocol and refuses a client offering only the
older "foxglove.websocket.v1"; the client offers both, newest first, as current Foxglove releases do.
"""

from __future__ import annotations

import base64
import json
import struct
import time

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.sync.client import connect

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA, FETCH_ASSET_RESPONSE = 0x01, 0x04


class FoxgloveClient:
    def __init__(self, url: str, timeout_s: float = 10.0) -> None:
        self._connection = connect(url, subprotocols=SUBPROTOCOLS, open_timeout=timeout_s, close_timeout=2, max_size=None)
        self.ws = self._connection.__enter__()
        self.timeout_s = timeout_s
        self.channels: dict[int, dict] = {}  # id -> advertised channel
        self.subscriptions: dict[int, int] = {}  # subscription id -> channel id
        self.assets: dict[int, tuple[int, str, bytes]] = {}
        self.messages: list[tuple[int, int, bytes, float]] = []  # (channel id, log time ns, payload, receive time s)
        self._classes: dict[int, type] = {}
        self.info = json.loads(self.ws.recv(timeout=timeout_s))
        assert self.info["op"] == "serverInfo", self.info

    def close(self) -> None:
        self._connection.__exit__(None, None, None)

    def __enter__(self) -> FoxgloveClient:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _read(self, timeout_s: float) -> None:
        frame = self.ws.recv(timeout=timeout_s)
        if isinstance(frame, str):
            message = json.loads(frame)
            if message["op"] == "advertise":
                self.channels.update({channel["id"]: channel for channel in message["channels"]})
            elif message["op"] == "unadvertise":
                for channel_id in message["channelIds"]:
                    self.channels.pop(channel_id, None)
            return
        opcode = frame[0]
        if opcode == MESSAGE_DATA:
            subscription, log_time_ns = struct.unpack_from("<IQ", frame, 1)
            self.messages.append((self.subscriptions[subscription], log_time_ns, bytes(frame[13:]), time.time()))
        elif opcode == FETCH_ASSET_RESPONSE:
            request, status, error_length = struct.unpack_from("<IBI", frame, 1)
            error = bytes(frame[10:10 + error_length]).decode()
            self.assets[request] = (status, error, bytes(frame[10 + error_length:]))

    def _until(self, predicate, timeout_s: float | None = None):
        deadline = time.monotonic() + (timeout_s or self.timeout_s)
        while True:
            value = predicate()
            if value:
                return value
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError("the Foxglove server did not send what was waited for")
            try:
                self._read(remaining)
            except TimeoutError:
                pass

    def topics(self, names=None) -> dict[str, dict]:
        """{topic: advertised channel}, waiting until `names` (if given) are all advertised."""
        by_topic = lambda: {channel["topic"]: channel for channel in self.channels.values()}  # noqa: E731
        self._until(lambda: by_topic() and set(names or ()) <= set(by_topic()))
        return by_topic()

    def subscribe(self, topics) -> None:
        channels = self.topics(topics)
        subscriptions = []
        for topic in topics:
            subscription = len(self.subscriptions) + 1
            self.subscriptions[subscription] = channels[topic]["id"]
            subscriptions.append({"id": subscription, "channelId": channels[topic]["id"]})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def next_message(self, topic: str, timeout_s: float | None = None):
        """The next message on `topic` (received after this call began), decoded; also its log time (ns)."""
        channel_id = self.topics([topic])[topic]["id"]
        start = len(self.messages)
        found = self._until(lambda: next((m for m in self.messages[start:] if m[0] == channel_id), None), timeout_s)
        return self.decode(channel_id, found[2]), found[1]

    def fetch_asset(self, uri: str, timeout_s: float | None = None) -> tuple[int, str, bytes]:
        """(status: 0 success / 1 error, error message, data)."""
        request = len(self.assets) + 1000
        self.ws.send(json.dumps({"op": "fetchAsset", "uri": uri, "requestId": request}))
        return self._until(lambda: self.assets.get(request), timeout_s)

    def decode(self, channel_id: int, payload: bytes):
        channel = self.channels[channel_id]
        if channel["encoding"] == "json":
            return json.loads(payload)
        cls = self._classes.get(channel_id)
        if cls is None:
            cls = self._classes[channel_id] = message_class(channel["schemaName"], base64.b64decode(channel["schema"]))
        return cls.FromString(payload)


def message_class(schema_name: str, file_descriptor_set: bytes) -> type:
    """The protobuf message class of `schema_name` from its FileDescriptorSet (the schema a server advertises)."""
    pool = descriptor_pool.DescriptorPool()
    for file in descriptor_pb2.FileDescriptorSet.FromString(file_descriptor_set).file:
        pool.Add(file)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))


def decoded(message):
    """A foxglove-sdk message (foxglove.messages.*, opaque from Python) as its protobuf message, to read its fields."""
    schema = message.get_schema()
    return message_class(schema.name, bytes(schema.data)).FromString(message.encode())
