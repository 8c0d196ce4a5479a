"""RecordedCamera: recorded RGB-D frames (a folder of PNG pairs or a ROS bag) behind the Camera interface.

A daemon reader thread publishes the pair its player says is current, `fps` times a second, stamped now:
the station sees a live camera ("newest value wins"), a held pair is re-sent, a bag keeps its recorded
timing. connect() checks the whole recording first (every pair's size and bit depth, the intrinsics) and
refuses it naming the file; a pair that fails to decode later is skipped and counted as a failed read.
"""

from __future__ import annotations

import logging
import time

from armlab.devices.recorded.configuration_recorded import RecordedCameraConfig
from armlab.devices.recorded.folder import RecordingError
from armlab.devices.recorded.players import open_player
from armlab.devices.threaded_camera import ThreadedCamera
from armlab.errors import DeviceAlreadyConnectedError

log = logging.getLogger(__name__)


class RecordedCamera(ThreadedCamera):
    """Plays a recording as a live camera; see RecordedCameraConfig for the options."""

    def __init__(self, config: RecordedCameraConfig) -> None:
        self.config = config
        super().__init__()
        self._player = None
        self._next_publish_s = 0.0
        self.description: str | None = None  # what is playing and where the intrinsics came from (after connect)

    def __str__(self) -> str:
        return f"RecordedCamera({self.config.source})"

    def connect(self) -> None:
        """Open and check the recording, start the reader thread and wait for the first frame."""
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self}: already connected; call close() before connecting again")

        try:
            self._player = open_player(self.config)
            self._intrinsics = self._player.intrinsics
            self.description = f"{self}: {self._player.describe()}"
            log.info("%s: %s", self, self.description)
            self._next_publish_s = time.monotonic()
            self._start_reader(self.config.warmup_timeout_s)
        except BaseException as error:
            ended = self._buffer.ended
            self._teardown()
            if isinstance(error, TimeoutError):
                raise (ended or ConnectionError(f"{self}: no frame within {self.config.warmup_timeout_s:.1f} s")) from error
            raise

    def close(self) -> None:
        """Stop the reader thread and close the recording. Safe to call twice."""
        self._teardown()

    def _teardown(self) -> None:
        self._stop_reader()
        if self._player is not None:
            self._player.close()
            self._player = None
        self._intrinsics = None

    def _step(self, stop) -> bool:
        """Publish the player's current pair at the configured rate; False ends the thread."""
        delay = self._next_publish_s - time.monotonic()
        if delay > 0 and stop.wait(delay):
            return False
        now = time.monotonic()
        self._next_publish_s = max(self._next_publish_s + 1.0 / self.config.fps, now - 1.0 / self.config.fps)
        try:
            color, depth = self._player.current(now)
        except EOFError as error:
            self._buffer.end(EOFError(f"{self}: {error}"))
            return False
        except RecordingError as error:
            log.warning("%s: %s", self, error)
            return self._read_failed(str(error))
        self._publish(color.copy(), depth.copy())  # consumers own their frame; the player keeps its pair
        return True
