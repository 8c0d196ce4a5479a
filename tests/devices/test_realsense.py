"""RealSenseCamera against a stand-in for pyrealsense2 (no RealSense in CI).

The stand-in mimics the calls the adapter makes (config/pipeline/align, depth scale, colour stream
intrinsics, frame sets) so these tests check the adapter's own logic: stream setup, depth units,
intrinsics, all-or-nothing connect with retry, and a lost device ending the stream with an error.
"""

from __future__ import annotations

import sys
import time
import types

import numpy as np
import pytest

from armlab.devices.factory import make_camera
from armlab.errors import DeviceNotConnectedError

DEPTH_SCALE_M = 0.00025  # the L515's depth unit


def _install_fake_pyrealsense2(monkeypatch, device_present: dict, fail_reads_after: int | None = None) -> dict:
    """A pyrealsense2 stand-in in sys.modules; `device_present["ok"]` decides whether start() works."""
    log: dict = {"streams": [], "devices": [], "stopped": 0, "frames": 0}
    rs = types.ModuleType("pyrealsense2")
    rs.stream = types.SimpleNamespace(color="color", depth="depth")
    rs.format = types.SimpleNamespace(bgr8="bgr8", z16="z16")

    class config:
        def enable_device(self, serial):
            log["devices"].append(serial)

        def enable_stream(self, stream, width, height, fmt, fps):
            log["streams"].append((stream, width, height, fmt, fps))

    class _Frame:
        def __init__(self, data):
            self._data = data

        def get_data(self):
            return self._data

        def __bool__(self):
            return True

    class _FrameSet:
        def __init__(self, index):
            self.index = index
            self.aligned = False

        def get_color_frame(self):
            return _Frame(np.full((6, 8, 3), self.index % 256, np.uint8))

        def get_depth_frame(self):
            if not self.aligned:
                return None  # the adapter must align depth to colour before using it
            raw = np.arange(48, dtype=np.uint16).reshape(6, 8) * 1000  # 0 … 47000 units
            return _Frame(raw)

    class align:
        def __init__(self, to_stream):
            assert to_stream == "color"

        def process(self, frames):
            frames.aligned = True
            return frames

    class pipeline:
        def start(self, cfg):
            if not device_present["ok"]:
                raise RuntimeError("No device connected")
            intrinsics = types.SimpleNamespace(width=8, height=6, fx=6.0, fy=6.5, ppx=3.9, ppy=2.8,
                                               coeffs=[0.1, 0.0, 0.0, 0.0, 0.0])
            stream_profile = types.SimpleNamespace(
                as_video_stream_profile=lambda: types.SimpleNamespace(get_intrinsics=lambda: intrinsics)
            )
            sensor = types.SimpleNamespace(get_depth_scale=lambda: DEPTH_SCALE_M)
            return types.SimpleNamespace(
                get_device=lambda: types.SimpleNamespace(first_depth_sensor=lambda: sensor),
                get_stream=lambda stream: stream_profile,
            )

        def wait_for_frames(self, timeout_ms):
            time.sleep(0.01)
            log["frames"] += 1
            if fail_reads_after is not None and log["frames"] > fail_reads_after:
                raise RuntimeError("Frame didn't arrive within 1000")
            return _FrameSet(log["frames"])

        def stop(self):
            log["stopped"] += 1

    rs.config, rs.pipeline, rs.align = config, pipeline, align
    monkeypatch.setitem(sys.modules, "pyrealsense2", rs)
    return log


def test_colour_and_aligned_depth_in_millimetres_with_device_intrinsics(monkeypatch):
    log = _install_fake_pyrealsense2(monkeypatch, {"ok": True})
    camera = make_camera({"type": "realsense", "serial": "f123", "width": 8, "height": 6, "fps": 30,
                          "depth_width": 8, "depth_height": 6})
    camera.connect()
    try:
        frame = camera.async_read(timeout_ms=2000)
        assert log["devices"] == ["f123"]
        assert log["streams"] == [("color", 8, 6, "bgr8", 30), ("depth", 8, 6, "z16", 30)]
        assert frame.color_bgr.shape == (6, 8, 3) and frame.color_bgr.dtype == np.uint8
        expected_mm = np.arange(48).reshape(6, 8) * 1000 * DEPTH_SCALE_M * 1000  # units → m → mm
        assert frame.depth_mm.dtype == np.uint16
        np.testing.assert_array_equal(frame.depth_mm, np.rint(expected_mm).astype(np.uint16))
        k = camera.intrinsics
        assert (k.width, k.height, k.fx, k.fy, k.cx, k.cy, k.dist) == (8, 6, 6.0, 6.5, 3.9, 2.8, (0.1, 0.0, 0.0, 0.0, 0.0))
        assert frame.intrinsics == k
        newer = camera.async_read(timeout_ms=2000)
        assert newer.sequence > frame.sequence
    finally:
        camera.close()
    assert log["stopped"] == 1 and not camera.is_connected


def test_no_device_is_a_connection_error_and_retry_works_once_plugged_in(monkeypatch):
    device = {"ok": False}
    _install_fake_pyrealsense2(monkeypatch, device)
    camera = make_camera({"type": "realsense"})
    with pytest.raises(ConnectionError, match=r"^RealSenseCamera\(first\): No device connected"):
        camera.connect()
    assert not camera.is_connected
    with pytest.raises(DeviceNotConnectedError):
        camera.read()
    device["ok"] = True
    camera.connect()
    try:
        assert camera.read().depth_mm is not None
    finally:
        camera.close()


def test_a_lost_device_ends_the_stream_with_an_error(monkeypatch):
    _install_fake_pyrealsense2(monkeypatch, {"ok": True}, fail_reads_after=3)
    camera = make_camera({"type": "realsense", "use_depth": False, "max_consecutive_failures": 2})
    camera.connect()
    try:
        with pytest.raises(ConnectionError, match=r"^RealSenseCamera\(first\): 2 consecutive failed reads"):
            for _ in range(10):
                frame = camera.read()
                assert frame.depth_mm is None  # colour only
    finally:
        camera.close()
