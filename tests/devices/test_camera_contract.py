"""The Camera contract, one test per clause, run against every camera backend that runs here.

Each backend is a CameraCase: `make_slow(tmp_path)` returns an unconnected camera producing about two
frames per second (so "no new frame yet" and "stale frame" are deterministic), and
`make_failing(tmp_path)` returns (camera, fix) where connect() fails until fix() is called. Adding a
backend is one entry in CASES.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

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
    make_slow: Callable[[Path], Camera]
    make_failing: Callable[[Path], tuple[Camera, Callable[[], None]]]


def _frames(count: int = 4) -> list[np.ndarray]:
    return [np.full((48, 64, 3), 30 * (index + 1), np.uint8) for index in range(count)]


def _opencv_slow(tmp_path: Path) -> Camera:
    path = write_video(tmp_path / "slow.avi", _frames(), fps=30.0)
    return OpenCVCamera(OpenCVCameraConfig(source=str(path), fps=SLOW_FPS))


def _opencv_failing(tmp_path: Path) -> tuple[Camera, Callable[[], None]]:
    path = tmp_path / "appears_later.avi"
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(path), fps=SLOW_FPS))
    return camera, lambda: write_video(path, _frames(), fps=30.0)


CASES = [
    CameraCase("opencv-video-file", _opencv_slow, _opencv_failing),
]


@pytest.fixture(params=CASES, ids=[case.name for case in CASES])
def case(request) -> CameraCase:
    return request.param


@pytest.fixture
def slow_camera(case, tmp_path):
    camera = case.make_slow(tmp_path)
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
    first = slow_camera.async_read(timeout_ms=2000)
    with pytest.raises(TimeoutError, match=f"^{_escape(slow_camera)}"):
        slow_camera.async_read(timeout_ms=50)  # the next frame is ~500 ms away
    second = slow_camera.async_read(timeout_ms=2000)
    assert second.sequence > first.sequence and second.timestamp_s > first.timestamp_s


def test_read_latest_never_waits_and_refuses_a_stale_frame(slow_camera):
    slow_camera.connect()
    fresh = slow_camera.read()  # just captured
    time.sleep(0.25)  # the next one is ~250 ms away: the newest frame is now ≥ 250 ms old
    started = time.monotonic()
    with pytest.raises(TimeoutError, match=f"^{_escape(slow_camera)}.*old"):
        slow_camera.read_latest(max_age_ms=100)
    assert time.monotonic() - started < 0.05  # refused at once, did not wait for a frame
    latest = slow_camera.read_latest(max_age_ms=5000)
    assert latest.sequence >= fresh.sequence


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
