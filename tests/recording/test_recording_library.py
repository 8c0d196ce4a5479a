"""The recordings folder without a simulation (a stand-in station: no arm, a camera slot fed by the test):
the disk budget deletes the oldest first and never the running recording; a cut-short MCAP is listed as truncated
and read up to its last complete chunk; a damaged file is listed as damaged; too little free disk refuses a start and
stops a running recording with its file complete; bad ids are NotFound; a second start is refused."""

from __future__ import annotations

import shutil
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from armlab.devices.camera import Frame, Intrinsics
from armlab.recording import (
    AlreadyRecording,
    DiskFull,
    NotRecording,
    RecordingBusy,
    RecordingLibrary,
    iter_messages,
    summarize,
)
from armlab.station.config import RecordingConfig
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import State
from armlab.store import NotFound

INTRINSICS = Intrinsics(64, 48, 50.0, 50.0, 32.0, 24.0)


class CameraOnlyStation:
    """What the sampler reads of a station, for a station without an arm: frames, perception, events, state."""

    has_arm = False
    backend = "test"
    calibration = None
    model = None

    class config:  # noqa: N801 - stands in for StationConfig
        workcell = "test"

    class intrinsics:  # noqa: N801
        @staticmethod
        def current():
            return INTRINSICS

    class gripper:  # noqa: N801
        @staticmethod
        def read_state():
            raise ConnectionError("no gripper")

    def __init__(self) -> None:
        self.events = EventLog()
        self.frames: NewestSlot[Frame] = NewestSlot()
        self.perception: NewestSlot = NewestSlot()
        self.state = State.IDLE
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._camera, daemon=True)

    def current_job(self):
        return None

    def _camera(self) -> None:
        sequence = 0
        while not self._stop.wait(0.01):
            sequence += 1
            color = np.full((48, 64, 3), sequence % 255, np.uint8)
            self.frames.publish(Frame(color, np.full((48, 64), 500 + sequence, np.uint16), time.time(), sequence, INTRINSICS))

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5)


def wait_for(predicate, timeout_s: float = 20.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


def config(**overrides) -> RecordingConfig:
    return RecordingConfig(**{"flush_interval_s": 0.05, "min_free_mb": 0.0, **overrides})


def record(library: RecordingLibrary, station, frames: int = 5) -> dict:
    library.start(station)
    wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) >= frames)
    return library.stop()


def test_a_recording_has_its_channels_with_their_schemas_and_ordered_times(tmp_path):
    library = RecordingLibrary(tmp_path, config())
    with CameraOnlyStation() as station:
        info = record(library, station)
    assert info["complete"] and not info["truncated"] and info["stop_reason"] == "stopped"
    with open(library.path(info["id"]), "rb") as stream:
        summary = make_reader(stream).get_summary()
    schemas = {channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()}
    for topic in ("/camera/color/compressed", "/camera/depth", "/camera/calibration", "/events"):
        assert schemas[topic] == {"/camera/color/compressed": "foxglove.CompressedImage", "/camera/depth": "foxglove.RawImage",
                                  "/camera/calibration": "foxglove.CameraCalibration", "/events": "foxglove.Log"}[topic]
    last: dict[str, int] = {}
    depth_values = []
    for topic, _, log_time, message in iter_messages(library.path(info["id"])):
        assert log_time >= last.get(topic, 0), topic
        last[topic] = log_time
        if topic == "/camera/depth":  # camera_scale 0.5 (the default): half the size, its calibration too
            assert (message.width, message.height, message.encoding) == (32, 24, "16UC1")
            depth_values.append(int(np.frombuffer(message.data, "<u2")[0]))
        if topic == "/camera/calibration":
            assert (message.width, message.height) == (32, 24)
            assert list(message.K) == pytest.approx([25.0, 0.0, 15.75, 0.0, 25.0, 11.75, 0.0, 0.0, 1.0])
    assert depth_values and all(value > 500 for value in depth_values)  # the frames' own depth, not zeros
    assert info["topics"]["/camera/color/compressed"] >= 5 and info["topics"]["/events"] >= 1  # the state


def test_start_twice_is_refused_and_the_running_recording_goes_on(tmp_path):
    library = RecordingLibrary(tmp_path, config())
    with CameraOnlyStation() as station:
        first = library.start(station)
        with pytest.raises(AlreadyRecording, match="already recording"):
            library.start(station)
        frames = library.active()["topics"].get("/camera/color/compressed", 0)
        wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) > frames + 3)
        ended = library.stop()
        with pytest.raises(NotRecording):
            library.stop()
    assert ended["id"] == first["id"] and ended["complete"]
    assert [item["id"] for item in library.list()] == [first["id"]]


def test_the_budget_deletes_the_oldest_recordings_first_never_the_running_one(tmp_path):
    ids = ["20261201T000000Z-aaaaaa", "20261202T000000Z-bbbbbb", "20261203T000000Z-cccccc", "20261204T000000Z-dddddd"]
    for recording_id in ids:
        (tmp_path / f"{recording_id}.mcap").write_bytes(b"x" * 400_000)
    library = RecordingLibrary(tmp_path, config(budget_mb=1.0))
    assert library.enforce_budget() == ids[:2]  # 1.6 MB -> 0.8 MB: the two oldest go
    assert sorted(path.stem for path in tmp_path.glob("*.mcap")) == ids[2:]
    with CameraOnlyStation() as station:  # a start makes room too, and the new one is never counted out
        library = RecordingLibrary(tmp_path, config(budget_mb=0.5))
        started = library.start(station)
        assert {path.stem for path in tmp_path.glob("*.mcap")} == {ids[3], started["id"]}
        library.stop()


def test_a_recording_alone_over_the_budget_stops_and_stays_readable(tmp_path):
    library = RecordingLibrary(tmp_path, config(budget_mb=0.002))  # 2 kB: the first flush is over it
    with CameraOnlyStation() as station:
        started = library.start(station)
        wait_for(lambda: library.active() is None)
    (info,) = library.list()
    assert info["id"] == started["id"] and "budget reached" in info["stop_reason"] and info["complete"]
    assert summarize(library.path(info["id"])).complete


def test_too_little_free_disk_refuses_a_start_and_stops_a_running_recording_complete(tmp_path):
    kept = tmp_path / "20261201T000000Z-aaaaaa.mcap"
    kept.write_bytes(b"earlier recording")
    free_mb = shutil.disk_usage(tmp_path).free / 1e6
    with CameraOnlyStation() as station:
        with pytest.raises(DiskFull, match="disk full"):
            RecordingLibrary(tmp_path, config(min_free_mb=free_mb * 10)).start(station)
        assert kept.read_bytes() == b"earlier recording" and len(list(tmp_path.glob("*.mcap"))) == 1
        library = RecordingLibrary(tmp_path, config())
        started = library.start(station)
        wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) >= 3)
        library._active.config = config(min_free_mb=free_mb * 10)  # the disk fills up while it records
        wait_for(lambda: library.active() is None)
    info = library.info(started["id"])
    assert info["stop_reason"].startswith("disk full") and info["complete"] and info["topics"]["/camera/color/compressed"] >= 3
    assert any("disk full" in event["message"] and event["level"] == "error" for event in station.events.since(0))


def _cut_short(tmp_path: Path) -> tuple[Path, int]:
    """A copy of a recording taken while it was still being written (as a SIGKILL leaves it), and how many
    colour frames had been flushed before the copy."""
    library = RecordingLibrary(tmp_path / "live", config(flush_interval_s=0.02))
    with CameraOnlyStation() as station:
        started = library.start(station)
        path = library.path(started["id"])
        wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) >= 10)
        library._active._writer.flush()
        flushed = library.active()["topics"]["/camera/color/compressed"]
        wait_for(lambda: library.active()["topics"]["/camera/color/compressed"] > flushed + 2)
        copy = tmp_path / "cut" / path.name
        copy.parent.mkdir()
        copy.write_bytes(path.read_bytes())
        library.stop()
    return copy, flushed


def test_a_cut_short_recording_is_listed_truncated_and_read_to_its_last_chunk(tmp_path):
    copy, flushed = _cut_short(tmp_path)
    summary = summarize(copy)
    assert not summary.complete and summary.truncated
    assert summary.topics["/camera/color/compressed"]["count"] >= flushed
    colour = [message for topic, _, _, message in iter_messages(copy, {"/camera/color/compressed"})]
    assert len(colour) >= flushed and all(message.format == "jpeg" for message in colour)
    (info,) = RecordingLibrary(copy.parent, config()).list()
    assert info["truncated"] and not info["complete"] and "cut short" in info["stop_reason"]
    assert info["topics"]["/camera/color/compressed"] >= flushed and info["duration_s"] > 0


def test_a_damaged_file_is_listed_as_damaged(tmp_path):
    (tmp_path / "20261201T000000Z-aaaaaa.mcap").write_bytes(b"not an mcap")
    (info,) = RecordingLibrary(tmp_path, config()).list()
    assert info["state"] == "damaged" and "not an MCAP" in info["stop_reason"]


@pytest.mark.parametrize("bad", ["../etc/passwd", "x", "20261201T000000Z-aaaaaa/../../x", "20261201T000000Z-zzzzzz", ""])
def test_bad_or_unknown_ids_are_not_found(tmp_path, bad):
    (tmp_path / "20261201T000000Z-aaaaaa.mcap").write_bytes(b"x")
    library = RecordingLibrary(tmp_path, config())
    with pytest.raises(NotFound):
        library.path(bad)
    with pytest.raises(NotFound):
        library.delete(bad)
    with pytest.raises(NotFound):
        library.path("20261201T000000Z-bbbbbb")  # well formed, not there


def test_the_running_recording_cannot_be_deleted(tmp_path):
    library = RecordingLibrary(tmp_path, config())
    with CameraOnlyStation() as station:
        started = library.start(station)
        with pytest.raises(RecordingBusy):
            library.delete(started["id"])
        library.stop()
    library.delete(started["id"])
    assert list(tmp_path.iterdir()) == []


class CountingSlot(NewestSlot):
    def __init__(self) -> None:
        super().__init__()
        self.waits = 0

    def wait_newer(self, version, timeout_s):
        self.waits += 1
        return super().wait_newer(version, timeout_s)


def test_with_no_camera_frame_yet_the_image_thread_waits(tmp_path):
    """Before the first frame the image loop waits on the slot (it spun at 100 % of a core: wait_newer(-1))."""
    station = CameraOnlyStation()  # its camera thread not started: no frame ever
    station.frames = CountingSlot()
    ticks = []
    station.current_job = lambda: ticks.append(1)  # the sample loop asks once per slow tick (30 Hz)
    library = RecordingLibrary(tmp_path, config())
    library.start(station)
    wait_for(lambda: len(ticks) >= 20)  # ~0.7 s of sampling: ~4 waits of 0.2 s, not millions of returns
    library.stop()
    assert 1 <= station.frames.waits < 200, station.frames.waits


class FillingFile:
    """A file object whose disk fills up: every write raises ENOSPC once `full` is set."""

    def __init__(self, file) -> None:
        self._file, self.full = file, False

    def write(self, data):
        if self.full:
            raise OSError(28, "No space left on device")
        return self._file.write(data)

    def __getattr__(self, name):
        return getattr(self._file, name)


def test_a_write_refused_by_a_full_disk_stops_the_recording_and_keeps_what_was_written(tmp_path, monkeypatch):
    from armlab.recording import mcap_file

    files: list[FillingFile] = []

    def filling_open(path, mode):
        files.append(FillingFile(open(path, mode)))  # noqa: SIM115 - the recording closes it
        return files[-1]

    monkeypatch.setattr(mcap_file, "open", filling_open, raising=False)
    library = RecordingLibrary(tmp_path, config())
    with CameraOnlyStation() as station:
        started = library.start(station)
        wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) >= 5)
        library._active._writer.flush()
        files[0].full = True  # the disk fills up
        wait_for(lambda: library.active() is None)
    info = library.info(started["id"])
    assert info["stop_reason"].startswith("disk full") and "No space left" in info["stop_reason"]
    assert info["topics"]["/camera/color/compressed"] >= 5 and info["truncated"]  # readable up to the last chunk
    assert any("disk full" in event["message"] and event["level"] == "error" for event in station.events.since(0))
