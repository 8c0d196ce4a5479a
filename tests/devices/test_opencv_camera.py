"""OpenCVCamera on real video files written by the test: order, looping, end of stream, intrinsics, config."""

from __future__ import annotations

import math
import threading

import numpy as np
import pytest

from armlab.config import validate_config
from armlab.devices.opencv import OpenCVCamera, OpenCVCameraConfig
from armlab.devices.opencv.camera_opencv import nominal_intrinsics
from armlab.devices.opencv.recording import write_video
from armlab.errors import ConfigError

LEVELS = (20, 90, 160, 230)  # one grey level per frame: survives MJPG compression to within a few units


def _video(tmp_path, count=None, size=(64, 48), fps=30.0):
    width, height = size
    frames = []
    for level in LEVELS[:count]:
        frame = np.full((height, width, 3), level, np.uint8)
        frame[:, :, 2] = 255 - level  # distinct channels: checks BGR order is preserved
        frames.append(frame)
    return write_video(tmp_path / "clip.avi", frames, fps=fps)


def _level(frame) -> int:
    return int(round(float(frame.color_bgr[:, :, 0].mean())))


def test_frames_arrive_in_file_order_and_the_file_loops(tmp_path):
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(_video(tmp_path)), fps=200.0))
    camera.connect()
    try:
        frames = [camera.read() for _ in range(2 * len(LEVELS) + 2)]
    finally:
        camera.close()
    sequences = [frame.sequence for frame in frames]
    assert sequences == sorted(set(sequences))  # strictly increasing, no repeats
    # Consecutive reads may skip a frame (newest wins), but each level must be one of the file's, and
    # reading past the last frame keeps going (it loops rather than ending).
    levels = [_level(frame) for frame in frames]
    nearest = [min(LEVELS, key=lambda lv: abs(lv - level)) for level in levels]
    assert all(abs(level - near) <= 4 for level, near in zip(levels, nearest))
    assert frames[-1].sequence > len(LEVELS)  # more frames than the file holds: it looped instead of ending
    assert len(frames) > len(LEVELS) and camera.is_connected is False
    first = frames[0]
    assert first.color_bgr.shape == (48, 64, 3) and first.depth_mm is None
    assert abs(int(first.color_bgr[0, 0, 2]) - (255 - _level(first))) <= 6  # red channel stayed red


def test_async_read_sees_every_frame_of_a_slow_file_then_end_of_stream(tmp_path):
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(_video(tmp_path)), fps=8.0, loop=False))
    camera.connect()
    try:
        levels = [_level(camera.async_read(timeout_ms=1000)) for _ in LEVELS]
        assert [min(LEVELS, key=lambda lv: abs(lv - level)) for level in levels] == list(LEVELS)
        with pytest.raises(EOFError, match=r"^OpenCVCamera\(.*end of the video file"):
            camera.async_read(timeout_ms=1000)
        with pytest.raises(EOFError):
            camera.read()
        assert _level(camera.read_latest(max_age_ms=10_000)) == levels[-1]  # the last frame is still there
    finally:
        camera.close()


def test_intrinsics_from_config_or_nominal_field_of_view(tmp_path):
    path = str(_video(tmp_path))
    nominal = OpenCVCamera(OpenCVCameraConfig(source=path, nominal_hfov_deg=90.0))
    nominal.connect()
    try:
        k = nominal.intrinsics
        assert (k.width, k.height) == (64, 48)
        assert math.isclose(k.fx, 32.0) and math.isclose(k.fy, 32.0)  # tan(45°) = 1 → fx = width / 2
        assert (k.cx, k.cy) == (31.5, 23.5)
        assert nominal.read().intrinsics == k
    finally:
        nominal.close()

    measured = OpenCVCamera(
        OpenCVCameraConfig(
            source=path,
            width=64,
            height=48,
            intrinsics={"fx": 70.0, "fy": 71.0, "cx": 30.0, "cy": 25.0, "dist": [0.1, -0.01, 0, 0, 0.001]},
        )
    )
    measured.connect()
    try:
        k = measured.intrinsics
        assert (k.fx, k.fy, k.cx, k.cy) == (70.0, 71.0, 30.0, 25.0) and k.dist == (0.1, -0.01, 0.0, 0.0, 0.001)
        np.testing.assert_allclose(k.K, [[70, 0, 30], [0, 71, 25], [0, 0, 1]])
    finally:
        measured.close()


def test_nominal_intrinsics_formula():
    k = nominal_intrinsics(1280, 720, 69.0)
    assert math.isclose(k.fx, 640 / math.tan(math.radians(34.5)))
    assert k.fx == k.fy and k.dist == (0.0,) * 5


def test_wrong_frame_size_fails_connect_without_leaking_a_thread(tmp_path):
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(_video(tmp_path)), width=640, height=480))
    before = set(threading.enumerate())
    with pytest.raises(ConnectionError, match=r"^OpenCVCamera\(.*64x48.*640x480"):
        camera.connect()
    assert not camera.is_connected and set(threading.enumerate()) <= before


def test_unopenable_file_is_a_clear_connection_error(tmp_path):
    bogus = tmp_path / "not_a_video.avi"
    bogus.write_bytes(b"this is not a video")
    camera = OpenCVCamera(OpenCVCameraConfig(source=str(bogus)))
    with pytest.raises(ConnectionError, match=r"^OpenCVCamera\("):
        camera.connect()
    assert not camera.is_connected


@pytest.mark.parametrize(
    "data, field",
    [
        ({"source": -1}, "source"),
        ({"source": "clip.avi", "width": 640}, "width and height"),
        ({"source": 0, "fps": float("nan")}, "fps"),
        ({"source": 0, "width": 64, "height": 48, "intrinsics": {"fx": -1, "fy": 1, "cx": 0, "cy": 0}}, "intrinsics.fx"),
        ({"source": 0, "intrinsics": {"fx": 1, "fy": 1, "cx": 0, "cy": 0}}, "need width and height"),
        ({"source": 0, "colour": True}, "colour"),
        ({"type": "realsense", "source": 0}, "type"),
    ],
)
def test_bad_config_is_a_config_error_naming_the_field(data, field):
    with pytest.raises(ConfigError, match=field):
        validate_config(data, OpenCVCameraConfig, "webcam.yaml")


def test_shipped_webcam_config_is_valid():
    from armlab.config import config_dir, load_config

    config = load_config(config_dir() / "cameras" / "webcam.yaml", OpenCVCameraConfig)
    assert config.type == "opencv" and config.source == 0
