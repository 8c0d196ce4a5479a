"""The Camera contract, one test per clause, run against every camera backend that runs here.

Each backend is a CameraCase: `make_slow(request)` returns an unconnected camera producing about two
frames per second (so "no new frame yet" and "stale frame" are deterministic), and
`make_failing(tmp_path)` returns (camera, fix) where connect() fails until fix() is called (None for
backends whose connect cannot fail, like the simulation). Adding a backend is one entry in CASES.
The sim camera runs in real-time mode (a render thread publishing frames), the mode the server uses.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from armlab.devices.camera import Camera, Frame
from armlab.devices.opencv import OpenCVCamera, OpenCVCameraConfig
from armlab.devices.opencv.recording import write_video
from armlab.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError

SLOW_FPS = 2.0


@dataclass(frozen=True)
class CameraCase:
    name: str
    make_slow: Callable[[pytest.FixtureRequest], Camera]
    make_failing: Callable[[Path], tuple[Camera, Callable[[], None]]] | None


def _frames(count: int = 4) -> list[np.ndarray]:
    return [np.full((48, 64, 3), 30 * (index + 1), np.uint8) for index in range(count)]


def _opencv_slow(request) -> Camera:
    path = write_video(request.getfixturevalue("tmp_path") / "slow.avi", _frames(), fps=30.0)
    return OpenCVCamera(OpenCVCameraConfig(source=str(path), fps=SLOW_FPS))


def _opencv_failing(tmp_path: Path) -> tuple[Camera, Callable[[], None]]:
    path = tmp_path / "appears_later.avi"
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(path), fps=SLOW_FPS))
    return camera, lambda: write_video(path, _frames(), fps=30.0)


def _recorded_slow(request) -> Camera:
    """A folder of two recorded RGB-D pairs (tests/devices/recorded_helpers.py) played at 2 frames/s. Its
    connect refuses bad input with a RecordingError naming the file (test_recorded_camera.py), not a
    ConnectionError: no failing case here."""
    from armlab.devices.recorded import RecordedCamera, RecordedCameraConfig
    from recorded_helpers import write_pairs

    folder = write_pairs(request.getfixturevalue("tmp_path") / "recording")
    return RecordedCamera(RecordedCameraConfig(source=str(folder), fps=SLOW_FPS))


@pytest.fixture(scope="module")
def slow_sim_workcell():
    """A real-time MuJoCo workcell whose camera renders 2 frames/s; its camera is left disconnected."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=True, camera_fps=SLOW_FPS))
    cell.start()
    cell.camera.close()  # the tests connect it themselves
    yield cell
    cell.close()


def _sim_slow(request) -> Camera:
    return request.getfixturevalue("slow_sim_workcell").camera


CASES = [
    CameraCase("opencv-video-file", _opencv_slow, _opencv_failing),
    CameraCase("sim", _sim_slow, None),
    CameraCase("recorded-folder", _recorded_slow, None),
]
FAILING_CASES = [case for case in CASES if case.make_failing is not None]


@pytest.fixture(params=CASES, ids=[case.name for case in CASES])
def case(request) -> CameraCase:
    return request.param


@pytest.fixture
def slow_camera(case, request):
    camera = case.make_slow(request)
    yield camera
    camera.close()


def test_connect_twice_raises_and_keeps_streaming(slow_camera):
    slow_camera.connect()
    with pytest.raises(DeviceAlreadyConnectedError, match=f"^{_escape(slow_camera)}"):
        slow_camera.connect()
    assert slow_camera.is_connected
    frame = slow_camera.async_read(timeout_ms=2000)
    assert isinstance(frame, Frame) and frame.color_bgr.ndim == 3 and frame.color_bgr.dtype == np.uint8


def test_read_before_connect_and_after_close_raise_not_connected(slow_camera):
    for method in (slow_camera.read, slow_camera.async_read, slow_camera.read_latest):
        with pytest.raises(DeviceNotConnectedError, match=f"^{_escape(slow_camera)}"):
            method()
    slow_camera.connect()
    slow_camera.close()
    slow_camera.close()  # safe twice
    assert not slow_camera.is_connected
    with pytest.raises(DeviceNotConnectedError):
        slow_camera.async_read()


def test_async_read_returns_each_frame_once_then_times_out(slow_camera):
    slow_camera.connect()
    slow_camera.async_read(timeout_ms=2000)  # drain whatever was buffered (may be old)
    first = slow_camera.async_read(timeout_ms=2000)  # so this one was captured just now
    with pytest.raises(TimeoutError, match=f"^{_escape(slow_camera)}"):
        slow_camera.async_read(timeout_ms=50)  # the next frame is ~500 ms away
    second = slow_camera.async_read(timeout_ms=2000)
    assert second.sequence > first.sequence and second.timestamp_s > first.timestamp_s


def test_read_latest_never_waits_and_refuses_a_stale_frame(slow_camera):
    slow_camera.connect()
    for _attempt in range(3):  # a loaded machine may deliver a late frame early: then try again
        fresh = slow_camera.read()  # just captured
        time.sleep(0.25)  # the next one is ~250 ms away: the newest frame is now ≥ 250 ms old
        try:
            early = slow_camera.read_latest(max_age_ms=100)
        except TimeoutError as error:  # refused at once: it did not wait for the next frame
            assert str(error).startswith(str(slow_camera)) and "old" in str(error)
            break
        assert early.sequence > fresh.sequence, "read_latest returned a frame older than max_age_ms"
    else:
        pytest.fail("frames kept arriving early; could not observe a stale frame")
    latest = slow_camera.read_latest(max_age_ms=5000)
    assert latest.sequence >= fresh.sequence


@pytest.mark.parametrize("case", FAILING_CASES, ids=[case.name for case in FAILING_CASES])
def test_failed_connect_releases_everything_and_retry_works(case, tmp_path):
    camera, fix = case.make_failing(tmp_path)
    threads_before = set(threading.enumerate())
    with pytest.raises(ConnectionError, match=f"^{_escape(camera)}"):
        camera.connect()
    assert not camera.is_connected
    assert set(threading.enumerate()) <= threads_before  # no reader thread left behind
    with pytest.raises(DeviceNotConnectedError):
        camera.read_latest()
    fix()
    try:
        camera.connect()
        assert camera.is_connected
        assert camera.async_read(timeout_ms=2000).color_bgr.size > 0
    finally:
        camera.close()


def _escape(camera: Camera) -> str:
    import re

    return re.escape(str(camera))
