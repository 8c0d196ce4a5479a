"""Live in Foxglove: the station's channels (channels.py, the ones a recording writes) on foxglove-sdk's WebSocket
server, fed by the same StationSampler, and the arm's URDF and meshes served as the server's assets.

`armlab serve --foxglove [PORT]` starts one LiveServer before the web server (a port that cannot be used stops
start-up in one line), attaches it to each station the app opens and stops it at exit. Foxglove connects to
ws://HOST:PORT; the shipped layout (config/foxglove/armlab_layout.json) loads the URDF from URDF_URI.

Who can see it: the Foxglove WebSocket protocol has no token. The server is view-only (it advertises no client
publishing, services or parameters: nothing sent to it reaches the station), but anyone who can open a connection
to the port sees the camera, the arm and the event log. It listens on loopback unless the operator names another
host AND passes allow_remote (`--foxglove-allow-remote`); check_address() refuses anything else.

Cost: a channel no client subscribes to is neither sampled nor encoded (StationSampler checks has_sinks()); the
sampler runs on its own threads; the SDK encodes on the calling (sampler) thread and sends from its own runtime.
bench/foxglove_live.py measures it.
"""

from __future__ import annotations

import ipaddress
import logging
from pathlib import Path
from typing import Any

import foxglove
from foxglove import Context

from armlab.errors import ConfigError
from armlab.recording.channels import StationChannels
from armlab.recording.sampler import StationSampler
from armlab.recording.urdf_frames import station_urdf
from armlab.station.arm_urdf import MeshSet
from armlab.station.config import SamplingConfig

log = logging.getLogger(__name__)

DEFAULT_PORT = 8765  # Foxglove's own default for a WebSocket connection
ASSET_ROOT = "package://armlab/"
URDF_URI = ASSET_ROOT + "urdf/arm.urdf"  # the station's arm, whichever it is (the layout names this one URI)
MESH_ROOT = ASSET_ROOT + "meshes/"  # + <arm>/<file>: the vendor's meshes the URDF names
MESH_DIR = Path(__file__).resolve().parents[2] / "web" / "meshes"  # the files the web page serves under /meshes/
LOOPBACK_NAMES = ("localhost",)


def is_loopback(host: str) -> bool:
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_address(host: str, port: int, allow_remote: bool = False) -> None:
    """ConfigError (one line naming the option) for a port outside 1-65535, or a host that is not loopback without
    allow_remote (the protocol has no token: see the module doc)."""
    if not isinstance(port, int) or isinstance(port, bool) or not 1 <= port <= 65535:
        raise ConfigError(f"--foxglove {port}: a port is a whole number from 1 to 65535")
    if not is_loopback(host) and not allow_remote:
        raise ConfigError(f"--foxglove-host {host}: not a loopback address; the Foxglove protocol has no token, so anyone "
                          "who can reach the port would see the camera and the arm. Add --foxglove-allow-remote to mean it "
                          "(or keep 127.0.0.1 and use an SSH tunnel)")


class LiveServer:
    """foxglove-sdk's WebSocket server on its own Context with StationChannels on it. start() binds (ConfigError if
    it cannot); attach(station) samples a station into it; detach(); stop()."""

    def __init__(self, host: str, port: int, config: SamplingConfig, *, allow_remote: bool = False, name: str = "ArmLab") -> None:
        check_address(host, port, allow_remote)
        self.host, self.requested_port, self.config, self.name = host, port, config, name
        self.context: Context | None = None
        self.channels: StationChannels | None = None
        self.server: Any = None
        self.sampler: StationSampler | None = None
        self.station: Any = None
        self._urdf: bytes | None = None

    def start(self) -> LiveServer:
        self.context = Context()
        self.channels = StationChannels.open(self.context)
        try:
            self.server = foxglove.start_server(name=self.name, host=self.host, port=self.requested_port, context=self.context,
                                                asset_handler=self._asset)
        except (RuntimeError, OverflowError, OSError) as error:
            self.channels.close()
            reason = str(error).removeprefix("FoxgloveError: ")
            raise ConfigError(f"--foxglove {self.requested_port}: cannot listen on {self.host}:{self.requested_port}: {reason}") from error
        return self

    @property
    def port(self) -> int:
        return self.server.port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    def attach(self, station: Any) -> None:
        """Sample `station` into the channels (on the sampler's threads) until detach()."""
        self.detach()
        self.station, self._urdf = station, None
        self.sampler = StationSampler(station, self.channels, self.config, thread_prefix="foxglove",
                                      on_failure=lambda reason: log.error("live Foxglove sampling stopped: %s", reason))
        self.sampler.start()

    def detach(self) -> None:
        sampler, self.sampler = self.sampler, None
        if sampler is not None:
            sampler.stop()
        self.station = None

    def stop(self) -> None:
        self.detach()
        if self.server is not None:
            self.server.stop()
            self.server = None
        if self.channels is not None:
            self.channels.close()
            self.channels = None

    # Assets -------------------------------------------------------------------------------------------

    def _asset(self, uri: str) -> bytes | None:
        """The URDF at URDF_URI, and the meshes it names under MESH_ROOT; None (the client is told "not found") for
        anything else: only the files of the station's arm's mesh set are served, no other path."""
        station = self.station
        if station is None or station.model is None:
            return None
        if uri == URDF_URI:
            if self._urdf is None:
                self._urdf = station_urdf(station, f"{MESH_ROOT}{station.model.name}/").encode()
            return self._urdf
        if uri.startswith(MESH_ROOT):
            arm, _, file = uri.removeprefix(MESH_ROOT).partition("/")
            meshes = MeshSet.load(station.model.name)
            if meshes is None or arm != station.model.name or file not in {visual["file"] for visual in meshes.visuals}:
                return None
            try:
                return (MESH_DIR / arm / file).read_bytes()
            except OSError:
                return None
        return None
