"""What a RecordedCamera plays: FolderPlayer (PNG pairs, each shown seconds_per_pair, or one held) and
BagPlayer (a ROS bag at its recorded timing). Both answer `current(now_s)` with the pair to show at that
moment of the monotonic clock, decode only the pairs they show, and know their intrinsics and where from."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from armlab.devices.recorded.bag import BagRecording
from armlab.devices.recorded.configuration_recorded import RecordedCameraConfig
from armlab.devices.recorded.folder import RecordingError, checked_pairs, read_pair
from armlab.devices.recorded.intrinsics_file import holds_intrinsics, read_intrinsics_file

log = logging.getLogger(__name__)

INTRINSICS_NAMES = ("intrinsics.json", "intrinsics.yaml", "intrinsics.yml")


def folder_intrinsics(folder: Path, given: str | None, size: tuple[int, int]):
    """(Intrinsics, description): the given file, else the folder's intrinsics.json, else the one file in the
    folder holding intrinsics; RecordingError when there are none (or several to choose from)."""
    if given is not None:
        return read_intrinsics_file(given, size)
    for name in INTRINSICS_NAMES:
        if (folder / name).is_file():
            return read_intrinsics_file(folder / name, size)
    candidates = [p for p in sorted(folder.iterdir()) if p.suffix in (".json", ".yaml", ".yml") and holds_intrinsics(p)]
    if len(candidates) == 1:
        return read_intrinsics_file(candidates[0], size)
    if candidates:
        raise RecordingError(
            f"{folder}: several files hold intrinsics ({', '.join(p.name for p in candidates)}): choose one with --intrinsics FILE"
        )
    raise RecordingError(
        f"{folder}: no intrinsics: add intrinsics.json (K, dist, image_size [width, height]) to the folder, "
        "or pass --intrinsics FILE (camera config: intrinsics:)"
    )


class FolderPlayer:
    """Pairs in name order, each for seconds_per_pair (one pair: held); a pair that fails to decode is skipped."""

    def __init__(self, config: RecordedCameraConfig) -> None:
        self.config = config
        folder = Path(config.source)
        self.pairs, size = checked_pairs(folder, config.frame)
        self.intrinsics, self.intrinsics_source = folder_intrinsics(folder, config.intrinsics, size)
        self._index = 0
        self._since_s: float | None = None
        self._shown: tuple[str, np.ndarray, np.ndarray] | None = None

    def describe(self) -> str:
        held = f"holding '{self.pairs[0].name}'" if len(self.pairs) == 1 else f"{len(self.pairs)} pairs, {self.config.seconds_per_pair:g} s each"
        return f"{held}; intrinsics from {self.intrinsics_source}"

    def current(self, now_s: float) -> tuple[np.ndarray, np.ndarray]:
        """The pair to show now (RecordingError naming a file that fails to decode: the next call moves on)."""
        if self._since_s is None:
            self._since_s = now_s
        elif len(self.pairs) > 1 and now_s - self._since_s >= self.config.seconds_per_pair:
            self._advance(now_s)
        pair = self.pairs[self._index]
        if self._shown is None or self._shown[0] != pair.name:
            try:
                color, depth = read_pair(pair)
            except RecordingError:
                if len(self.pairs) > 1:
                    self._advance(now_s)
                raise
            self._shown = (pair.name, color, depth)
        return self._shown[1], self._shown[2]

    def _advance(self, now_s: float) -> None:
        if self._index + 1 >= len(self.pairs) and not self.config.loop:
            raise EOFError(f"the last of {len(self.pairs)} pairs was shown (loop is off)")
        self._index = (self._index + 1) % len(self.pairs)
        self._since_s = now_s

    def close(self) -> None:
        self._shown = None


class BagPlayer:
    """A bag's colour/depth pairs at their recorded timing (times playback_speed), looping if configured."""

    def __init__(self, config: RecordedCameraConfig) -> None:
        self.config = config
        self.bag = BagRecording(Path(config.source), config.color_topic, config.depth_topic, config.info_topic, config.max_skew_s)
        try:
            first = next(self.bag.pairs(), None)
            if first is None:
                raise RecordingError(
                    f"{config.source}: no colour/depth pair within {config.max_skew_s * 1000:.0f} ms on {self.bag.color_topic} and {self.bag.depth_topic}"
                )
            color, depth = self._checked(first)
            size = (color.shape[1], color.shape[0])
            if config.intrinsics is not None:
                self.intrinsics, self.intrinsics_source = read_intrinsics_file(config.intrinsics, size)
            else:
                self.intrinsics = self.bag.intrinsics()
                if self.intrinsics is None:
                    raise RecordingError(f"{config.source}: no camera_info topic and no intrinsics file: pass --intrinsics FILE")
                if (self.intrinsics.width, self.intrinsics.height) != size:
                    raise RecordingError(
                        f"{config.source}: {self.bag.info_topic} is for {self.intrinsics.width}x{self.intrinsics.height} images, "
                        f"{self.bag.color_topic} is {size[0]}x{size[1]}"
                    )
                self.intrinsics_source = f"{self.bag.info_topic} (camera_info)"
        except BaseException:
            self.bag.close()
            raise
        self._restart()

    def describe(self) -> str:
        return f"{self.bag.color_topic} + {self.bag.depth_topic}; intrinsics from {self.intrinsics_source}"

    def _checked(self, pair) -> tuple[np.ndarray, np.ndarray]:
        _, decode = pair
        color, depth = decode()
        if depth.shape != color.shape[:2]:
            raise RecordingError(
                f"{self.config.source}: {self.bag.depth_topic} is {depth.shape[1]}x{depth.shape[0]}, {self.bag.color_topic} is "
                f"{color.shape[1]}x{color.shape[0]}: depth must be aligned to colour (the same size)"
            )
        return color, depth

    def _restart(self) -> None:
        self._pairs = self.bag.pairs()
        self._next = next(self._pairs, None)
        self._start_bag_s = self._next[0] if self._next is not None else 0.0
        self._start_s: float | None = None
        self._shown: tuple[np.ndarray, np.ndarray] | None = None

    def current(self, now_s: float) -> tuple[np.ndarray, np.ndarray]:
        if self._start_s is None:
            self._start_s = now_s
        bag_now_s = self._start_bag_s + (now_s - self._start_s) * self.config.playback_speed
        due = None
        while self._next is not None and self._next[0] <= bag_now_s:  # newest due pair wins; older ones are never decoded
            due, self._next = self._next, next(self._pairs, None)
        if due is not None:
            self._shown = self._checked(due)
        elif self._next is None and self._shown is not None and bag_now_s > self._start_bag_s:
            if not self.config.loop:
                raise EOFError("end of the bag (loop is off)")
            self._restart()
            return self.current(now_s)
        if self._shown is None:
            raise RecordingError(f"{self.config.source}: no pair to show yet")
        return self._shown

    def close(self) -> None:
        self.bag.close()


def open_player(config: RecordedCameraConfig):
    """A FolderPlayer for a folder of PNG pairs, else a BagPlayer (a rosbag2 folder has metadata.yaml)."""
    source = Path(config.source)
    if not source.exists():
        raise RecordingError(f"{source}: no such folder or bag")
    if source.is_dir() and not (source / "metadata.yaml").exists():
        return FolderPlayer(config)
    if config.frame is not None:
        raise RecordingError(f"{source}: frame: '{config.frame}' holds a pair of a folder; a bag plays its pairs in time")
    return BagPlayer(config)
