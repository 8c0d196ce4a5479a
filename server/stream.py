"""The websocket stream: one encoder thread, per-client "newest value wins" slots, ack flow control.

The FrameEncoder thread encodes each new camera frame once per distinct ViewKey that some client
watches and hands the result to the StreamHub on the event loop. Each client has one sender task that
wakes on news and sends the newest telemetry, new events, the newest calibration and — only once the
client acknowledged the previous frame — the newest frame of its view. Nothing queues per client, so
a slow or stalled client holds at most one frame in flight and never slows anyone else.

A session with the control token is a controller named by `?controller=` (else a name of its own): it
may take the control lease, start and stop hold-to-run jogs (jog, jog_cartesian, jog_stop: the REST routes'
station calls and checks, each answered by a jog_reply), its heartbeats keep its jog going, and when its last
session closes its jog ramps down and the lease it holds is released. Calls into the station run off the event loop (e-stop on the
app's safety pool). A session's e-stop is never queued behind its other messages: acks, view changes and
e-stops are handled as they arrive, the station calls of other commands and heartbeats in order on the
session's own task.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import logging
import struct
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Annotated, Union

from pydantic import Field, TypeAdapter, ValidationError
from starlette.websockets import WebSocket, WebSocketDisconnect

from armlab.errors import is_internal
from armlab.station.arm_info import arm_info, station_workcell_name
from armlab.station.core import Station
from armlab.station.lease import checked_controller
from armlab.station.perception import _Worker
from armlab.workcell import load_workcell
from server.errors import error_status
from server.models import (
    AckMessage,
    CommandMessage,
    HeartbeatMessage,
    JogCartesianMessage,
    JogMessage,
    JogStopMessage,
    ViewMessage,
)
from server.stream_models import CLIENT_MESSAGES, message_type
from server.views import ViewKey, compose_view, encode_jpeg

log = logging.getLogger(__name__)


def _said(error: Exception) -> str:
    """What a websocket client is told of a command's failure; a bug (armlab.errors.is_internal) is logged
    with its traceback and reported as an internal error, as the HTTP routes answer 500."""
    if is_internal(error):
        log.error("internal error in a websocket command", exc_info=error)
        return f"internal error ({type(error).__name__}); the server log has the traceback"
    return str(error)


# What a client may send: validated strictly (server/models.py), dispatched on "type".
CLIENT_MESSAGE = TypeAdapter(Annotated[Union[CLIENT_MESSAGES], Field(discriminator="type")])  # noqa: UP007 - a tuple
_CLIENT_TYPES = [message_type(model) for model in CLIENT_MESSAGES]
_SESSION_NUMBERS = itertools.count(1)
JOG_MESSAGES = (JogMessage, JogCartesianMessage, JogStopMessage)
_JOG_TYPES = frozenset(message_type(model) for model in JOG_MESSAGES)
MAX_QUEUED_CALLS = 32  # a session's station calls waiting behind a slow one; more are refused with an error event


def _message_error(text: str, error: ValidationError) -> str:
    """One line for the client: what was wrong with its message."""
    first = error.errors()[0]
    where = ".".join(str(part) for part in first.get("loc", ()))
    expected = f"{', '.join(_CLIENT_TYPES[:-1])} or {_CLIENT_TYPES[-1]}"
    return f"bad message {text[:80]!r}: {where + ': ' if where else ''}{first.get('msg')} (expected type {expected})"


def _jog_request(text: str) -> dict | None:
    """A message that failed validation but is a jog request (its type says so): its JSON object, for the reply's id
    (an id that is not an int is left out); None otherwise."""
    try:
        parsed = json.loads(text)
    except ValueError:
        return None
    kind = parsed.get("type") if isinstance(parsed, dict) else None
    if not isinstance(kind, str) or kind not in _JOG_TYPES:
        return None
    message_id = parsed.get("id")
    valid_id = isinstance(message_id, int) and not isinstance(message_id, bool) and 0 <= message_id < 2**31
    return {**parsed, "id": message_id if valid_id else None}


@dataclass(frozen=True)
class EncodedFrame:
    """A ready-to-send binary message: [uint32 LE header length][JSON header][JPEG]."""

    key: ViewKey
    seq: int
    capture_time_s: float
    message: bytes


def pack_frame(header: dict, jpeg: bytes) -> bytes:
    header_bytes = json.dumps(header, separators=(",", ":")).encode()
    return struct.pack("<I", len(header_bytes)) + header_bytes + jpeg


def unpack_frame(message: bytes) -> tuple[dict, bytes]:
    """(header, jpeg) of a binary frame message (used by the Python client and tests)."""
    (length,) = struct.unpack_from("<I", message, 0)
    return json.loads(message[4 : 4 + length]), message[4 + length :]


class FrameEncoder(_Worker):
    """Encodes each new frame once per watched ViewKey; `on_frame(EncodedFrame)` gets the result."""

    name = "stream-encoder"

    def __init__(self, station: Station, on_frame, quality: int) -> None:
        super().__init__()
        self.station = station
        self.on_frame = on_frame
        self.quality = quality
        self._watched: Counter[ViewKey] = Counter()
        self._watch_lock = threading.Lock()
        self._changed = threading.Event()

    def watch(self, key: ViewKey) -> None:
        with self._watch_lock:
            self._watched[key] += 1
        self._changed.set()

    def unwatch(self, key: ViewKey) -> None:
        with self._watch_lock:
            self._watched[key] -= 1
            if self._watched[key] <= 0:
                del self._watched[key]

    def watched(self) -> list[ViewKey]:
        with self._watch_lock:
            return list(self._watched)

    def _run(self) -> None:
        version = 0
        while not self._stop.is_set():
            frame, version = self.station.frames.wait_newer(version, timeout_s=0.5)
            keys = self.watched()
            if frame is None or not keys:
                continue
            perception, _ = self.station.perception.get()
            calibration = self.station.calibration
            for key in keys:
                image = compose_view(frame, key, perception, calibration, self.station.perception_config)
                header = {
                    "type": "frame",
                    "seq": int(frame.sequence),
                    "capture_time_s": float(frame.timestamp_s),
                    "width": int(image.shape[1]),
                    "height": int(image.shape[0]),
                    "view": key.view,
                }
                message = pack_frame(header, encode_jpeg(image, self.quality))
                self.on_frame(EncodedFrame(key, int(frame.sequence), float(frame.timestamp_s), message))


@dataclass(eq=False)
class ClientSession:
    """One websocket client's slots: what it watches, what it was last sent, what it has acknowledged."""

    websocket: WebSocket
    can_control: bool
    controller: str = ""
    key: ViewKey = field(default_factory=ViewKey)
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    awaiting_ack: int | None = None
    last_frame_seq: int = -1
    telemetry_version: int = 0
    calibration_version: int = 0
    event_seq: int = 0
    frames_sent: int = 0
    calls: asyncio.Queue = field(default_factory=lambda: asyncio.Queue(MAX_QUEUED_CALLS))  # commands, heartbeats
    queued_heartbeats: int = 0  # heartbeats in `calls`: one waiting behind another is superseded by it


class StreamHub:
    """Lives on the event loop; threads hand it news through call_soon_threadsafe."""

    def __init__(self, station: Station, jpeg_quality: int, safety_pool=None) -> None:
        self.station = station
        self.safety_pool = safety_pool  # None: the loop's default executor
        self._workcell: dict | None = None
        self._arm: dict | None = None  # arm_info(station), read once off the loop (it loads the workcell file)
        self._limits_info: dict | None = None  # _limits(), read once off the loop (the motion config file)
        self.loop: asyncio.AbstractEventLoop | None = None
        self.clients: set[ClientSession] = set()
        self.frames: dict[ViewKey, EncodedFrame] = {}
        self.telemetry_text: str | None = None
        self.telemetry_version = 0
        self.calibration_text: str | None = None
        self.calibration_version = 0
        self.encoder = FrameEncoder(station, self._from_thread(self._on_frame), jpeg_quality)

    def _from_thread(self, callback):
        def forward(*args) -> None:
            loop = self.loop
            if loop is not None and not loop.is_closed():
                try:
                    loop.call_soon_threadsafe(callback, *args)
                except RuntimeError:  # loop closing
                    pass

        return forward

    def start(self) -> None:
        self.loop = asyncio.get_running_loop()
        telemetry = self._from_thread(self._on_telemetry)
        events = self._from_thread(self._wake_all)
        calibration = self._from_thread(self._on_calibration)
        self._listeners = (
            (self.station.telemetry, lambda value, version: telemetry(json.dumps({"type": "telemetry", **value}))),
            (self.station.events, lambda event: events()),
            (self.station.calibration_slot, lambda value, version: calibration(json.dumps({"type": "calibration", **value}))),
        )
        for source, listener in self._listeners:
            source.add_listener(listener)
        self.encoder.start()

    def stop(self) -> None:
        for source, listener in getattr(self, "_listeners", ()):
            source.remove_listener(listener)
        self._listeners = ()
        self.encoder.stop()
        self.loop = None

    # Called on the loop ---------------------------------------------------------------------------

    def _on_frame(self, encoded: EncodedFrame) -> None:
        self.frames[encoded.key] = encoded
        for client in self.clients:
            if client.key == encoded.key:
                client.wake.set()

    def _on_telemetry(self, text: str) -> None:
        self.telemetry_text, self.telemetry_version = text, self.telemetry_version + 1
        self._wake_all()

    def _on_calibration(self, text: str) -> None:
        self.calibration_text, self.calibration_version = text, self.calibration_version + 1
        self._wake_all()

    def _forget_unwatched(self) -> None:
        """Drop cached frames of views nobody watches any more (bounded memory as views come and go)."""
        watched = {client.key for client in self.clients}
        for key in [key for key in self.frames if key not in watched]:
            del self.frames[key]

    def _wake_all(self) -> None:
        for client in self.clients:
            client.wake.set()

    # One client -----------------------------------------------------------------------------------

    def _workcell_info(self) -> dict:
        """The geometry of the station's workcell (HelloMessage.workcell): its config's, else perception's."""
        return load_workcell(station_workcell_name(self.station)).to_wire()

    def _limits(self) -> dict:
        """Limits of operator inputs (HelloMessage.limits): the longest manual move, the hold-to-run jogs' top speeds, hold
        and the Cartesian jog's acceleration."""
        limits = {"max_moving_time_s": float(self.station.config.max_moving_time_s)}
        motion = getattr(self.station, "motion_config", None)
        if motion is not None:
            limits.update(jog_max_speed_rad_s=float(motion.jog_max_speed_rad_s), jog_hold_s=float(motion.jog_hold_s),
                          jog_max_speed_m_s=float(motion.jog_max_speed_m_s), jog_accel_m_s2=float(motion.jog_accel_m_s2))
        return limits

    @staticmethod
    def session_controller(requested: str | None) -> str:
        """The controller name of a new session: the one it asked for (validated), else its own 'ws-<n>'."""
        return checked_controller(requested) if requested else f"ws-{next(_SESSION_NUMBERS)}"

    async def serve(self, websocket: WebSocket, can_control: bool, controller: str | None = None) -> None:
        client = ClientSession(websocket, can_control, controller=controller or self.session_controller(None),
                               event_seq=self.station.events.last_seq)
        if self._workcell is None:  # read once, off the event loop (a config file)
            self._workcell = await self._off_loop(self._workcell_info)
        if self._arm is None:  # likewise: the gripper type comes from the workcell file
            self._arm = await self._off_loop(arm_info, self.station)
        if self._limits_info is None:  # the motion config may be read from its file
            self._limits_info = await self._off_loop(self._limits)
        hello = {"type": "hello", "server_time_s": time.time(), "can_control": can_control,
                 "controller": client.controller if can_control else None, "backend": self.station.backend,
                 "workcell": self._workcell, "arm": self._arm, "limits": self._limits_info}
        await websocket.send_text(json.dumps(hello))
        calibration = await self._off_loop(lambda: self.station.calibration_info)
        await websocket.send_text(json.dumps({"type": "calibration", **calibration}))
        client.calibration_version = self.calibration_version
        self.clients.add(client)
        self.encoder.watch(client.key)
        tasks = {asyncio.create_task(self._send_loop(client)), asyncio.create_task(self._receive_loop(client)),
                 asyncio.create_task(self._call_loop(client))}
        try:
            # Whichever ends first (client gone, send failed) ends the session.
            done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            for task in done:
                error = task.exception()
                if error is not None and not isinstance(error, (WebSocketDisconnect, ConnectionError, RuntimeError)):
                    log.warning("websocket session ended by %r", error)
        finally:
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            self.clients.discard(client)
            self.encoder.unwatch(client.key)
            self._forget_unwatched()
            if client.can_control and not any(other.controller == client.controller for other in self.clients):
                await self._off_loop(self.station.stop_jog, client.controller)  # its held jog ramps down now
                await self._off_loop(self.station.release_control, client.controller, "released (disconnected)")

    async def _send_loop(self, client: ClientSession) -> None:
        websocket = client.websocket
        while True:
            await client.wake.wait()
            client.wake.clear()
            if self.telemetry_version > client.telemetry_version and self.telemetry_text is not None:
                client.telemetry_version = self.telemetry_version
                await websocket.send_text(self.telemetry_text)
            for event in self.station.events.since(client.event_seq):
                client.event_seq = event["seq"]
                await websocket.send_text(json.dumps({"type": "event", **{k: v for k, v in event.items() if k != "seq"}}))
            if self.calibration_version > client.calibration_version and self.calibration_text is not None:
                client.calibration_version = self.calibration_version
                await websocket.send_text(self.calibration_text)
            encoded = self.frames.get(client.key)
            if client.awaiting_ack is None and encoded is not None and encoded.seq != client.last_frame_seq:
                client.awaiting_ack = client.last_frame_seq = encoded.seq
                client.frames_sent += 1
                await websocket.send_bytes(encoded.message)

    async def _receive_loop(self, client: ClientSession) -> None:
        """Handle the client's messages; a malformed one gets an error event and the session goes on."""
        while True:
            message = await client.websocket.receive()
            if message["type"] == "websocket.disconnect":
                raise WebSocketDisconnect(message.get("code", 1000), message.get("reason"))
            text = message.get("text")
            if text is None:
                await self._reply_error(client, "binary messages are not accepted: send JSON text (type ack, view or command)")
                continue
            try:
                parsed = CLIENT_MESSAGE.validate_json(text)
            except ValidationError as error:
                if (jog := _jog_request(text)) is not None:  # a refused jog is answered like one: the page ends its hold
                    await self._jog_reply(client, jog.get("id"), 422, "invalid", _message_error(text, error))
                else:
                    await self._reply_error(client, _message_error(text, error))
                continue
            if isinstance(parsed, AckMessage):
                if parsed.seq == client.awaiting_ack:
                    client.awaiting_ack = None
                    client.wake.set()
            elif isinstance(parsed, ViewMessage):
                await self._change_view(client, parsed.view, parsed.layers)
            elif isinstance(parsed, CommandMessage) and parsed.name == "estop":
                await self._command(client, "estop")  # at once: never behind a slow command of this session
            else:
                try:
                    client.calls.put_nowait(parsed)
                    client.queued_heartbeats += isinstance(parsed, HeartbeatMessage)
                except asyncio.QueueFull:
                    await self._reply_error(client, f"too many messages waiting ({MAX_QUEUED_CALLS}): {text[:80]!r} dropped")

    async def _call_loop(self, client: ClientSession) -> None:
        """The session's commands (but e-stop) and heartbeats, one at a time in the order they came. A heartbeat with
        another one queued behind it is skipped: the later one says the same, later; a backlog of heartbeats behind a
        slow call would otherwise keep a hold-to-run jog going after the page stopped beating."""
        while True:
            parsed = await client.calls.get()
            if isinstance(parsed, HeartbeatMessage):
                client.queued_heartbeats -= 1
                if client.can_control and client.queued_heartbeats == 0:
                    try:
                        await self._off_loop(self.station.heartbeat, client.controller)
                    except Exception as error:  # noqa: BLE001 - reported; the session goes on
                        await self._reply_error(client, f"heartbeat: {_said(error)}")
            elif isinstance(parsed, JOG_MESSAGES):
                await self._jog(client, parsed)
            else:
                await self._command(client, parsed.name)

    async def _jog(self, client: ClientSession, message) -> None:
        """A jog, jog_cartesian or jog_stop message: the station call of the REST route (the same checks and lease),
        answered by a jog_reply with the status and error code the route would give."""
        if not client.can_control:
            await self._jog_reply(client, message.id, 401, "unauthorized",
                                  f"{message.type} refused: this connection is view-only (no control token)")
            return
        station, source = self.station, client.controller
        if isinstance(message, JogMessage):
            call = lambda: station.jog(message.velocity_rad_s, source=source, speed_percent=message.speed_percent)  # noqa: E731
        elif isinstance(message, JogCartesianMessage):
            call = lambda: station.jog_cartesian(message.axis, message.velocity_m_s, source=source,  # noqa: E731
                                                 speed_percent=message.speed_percent)
        else:
            call = lambda: station.stop_jog(source=source)  # noqa: E731
        try:
            await self._off_loop(call)
        except Exception as error:  # noqa: BLE001 - answered to the client
            status_code, code = error_status(error)
            await self._jog_reply(client, message.id, status_code, code, _said(error))
            return
        await self._jog_reply(client, message.id, 200, None, None)

    async def _jog_reply(self, client: ClientSession, message_id: int | None, status_code: int, code: str | None,
                         message: str | None) -> None:
        reply = {"type": "jog_reply", "id": message_id, "ok": status_code == 200, "status_code": status_code, "code": code,
                 "message": message}
        await client.websocket.send_text(json.dumps(reply))

    async def _change_view(self, client: ClientSession, view: str, layers: list[str]) -> None:
        try:
            key = ViewKey.make(view, layers)
        except (ValueError, TypeError) as error:
            await self._reply_error(client, str(error))
            return
        if key != client.key:
            self.encoder.watch(key)
            self.encoder.unwatch(client.key)
            client.key = key
            self._forget_unwatched()
            client.awaiting_ack = None  # the old view's frame needs no ack any more
            client.last_frame_seq = -1
            client.wake.set()

    async def _off_loop(self, function, *args):
        """Run a station call on a worker thread (the station's lock is short, but never on the loop)."""
        return await asyncio.to_thread(function, *args)

    async def _command(self, client: ClientSession, name: str) -> None:
        if not client.can_control and name != "estop":  # stopping is always allowed, even view-only
            await self._reply_error(client, f"command '{name}' refused: this connection is view-only (no control token)")
            return
        actions = {
            "estop": self.station.estop, "reset": self.station.reset, "cancel": self.station.cancel_job,
            "take_control": self.station.take_control, "release_control": self.station.release_control,
        }
        if name not in actions:
            await self._reply_error(client, f"unknown command {name!r}; the websocket accepts {', '.join(actions)}")
            return
        try:
            if name == "estop":
                await asyncio.get_running_loop().run_in_executor(self.safety_pool, actions[name], client.controller)
            else:
                await self._off_loop(actions[name], client.controller)
        except Exception as error:  # noqa: BLE001 - reported to the client as an event
            await self._reply_error(client, _said(error))

    async def _reply_error(self, client: ClientSession, message: str) -> None:
        await client.websocket.send_text(json.dumps({"type": "event", "level": "error", "kind": "general", "message": message, "time_s": time.time()}))
