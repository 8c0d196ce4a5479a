"""RealSenseCamera: colour + aligned depth from pyrealsense2 behind the Camera interface.

pyrealsense2 is an optional extra (`pip install 'armlab[realsense]'`); it is imported inside connect()
so nothing else pulls it in. The reader thread, buffering and error contract are the OpenCV backend's
(ThreadedCamera): only the device calls below are RealSense-specific, and they are kept thin because no
test machine has the hardware.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.devices.realsense.configuration_realsense import RealSenseCameraConfig
from armlab.devices.threaded_camera import ThreadedCamera
from armlab.errors import DeviceAlreadyConnectedError


class RealSenseNotInstalledError(ImportError):
    """pyrealsense2 is missing; the message says how to install it."""


def import_pyrealsense2(owner: str = "RealSenseCamera"):
    """The pyrealsense2 module, or RealSenseNotInstalledError (message prefixed by owner) saying what to install."""
    try:
        import pyrealsense2
    except ImportError as error:
        raise RealSenseNotInstalledError(
            f"{owner}: needs pyrealsense2: install it with `pip install 'armlab[realsense]'` "
            "(or `pip install pyrealsense2`; on ARM boards build librealsense with its Python bindings)"
        ) from error
    return pyrealsense2


class RealSenseCamera(ThreadedCamera):
    """A RealSense camera streaming colour (BGR8) and, optionally, depth aligned to colour (mm)."""

    def __init__(self, config: RealSenseCameraConfig) -> None:
        self.config = config
        self._device_serial: str | None = None  # read at connect: names the camera (stored intrinsics are keyed by it)
        super().__init__()
        self._rs = None
        self._pipeline = None
        self._align = None
        self._depth_scale_mm = 1.0

    def __str__(self) -> str:
        return f"RealSenseCamera({self.config.serial or self._device_serial or 'first'})"

    def connect(self) -> None:
        """Start the pipeline, read the factory intrinsics, start the reader; all-or-nothing."""
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self}: already connected; call close() before connecting again")
        rs = import_pyrealsense2(str(self))
        try:
            self._rs = rs
            rs_config = rs.config()
            if self.config.serial:
                rs_config.enable_device(self.config.serial)
            cfg = self.config
            rs_config.enable_stream(rs.stream.color, cfg.width, cfg.height, rs.format.bgr8, cfg.fps)
            if cfg.use_depth:
                rs_config.enable_stream(rs.stream.depth, cfg.depth_width, cfg.depth_height, rs.format.z16, cfg.fps)
            self._pipeline = rs.pipeline()
            profile = self._pipeline.start(rs_config)
            try:
                self._device_serial = str(profile.get_device().get_info(rs.camera_info.serial_number))
            except (AttributeError, RuntimeError):  # an SDK or device that does not report it
                self._device_serial = None
            if cfg.use_depth:
                self._align = rs.align(rs.stream.color)
                depth_scale_m = profile.get_device().first_depth_sensor().get_depth_scale()
                self._depth_scale_mm = depth_scale_m * 1000.0
            stream = profile.get_stream(rs.stream.color).as_video_stream_profile().get_intrinsics()
            self._intrinsics = Intrinsics(
                stream.width, stream.height, stream.fx, stream.fy, stream.ppx, stream.ppy, tuple(stream.coeffs[:5])
            )
            self._start_reader(cfg.warmup_timeout_s)
        except BaseException as error:
            self._teardown()
            if isinstance(error, TimeoutError):
                raise ConnectionError(f"{self}: no frame within {self.config.warmup_timeout_s:.0f} s") from error
            if isinstance(error, RuntimeError):  # pyrealsense2 reports device problems as RuntimeError
                raise ConnectionError(f"{self}: {error}") from error
            raise

    def close(self) -> None:
        """Stop the reader and the pipeline. Safe to call twice."""
        self._teardown()

    def _teardown(self) -> None:
        self._stop_reader()
        if self._pipeline is not None:
            try:
                self._pipeline.stop()
            except RuntimeError:
                pass  # never started
            self._pipeline = None
        self._align = None
        self._intrinsics = None

    def _step(self, stop) -> bool:
        try:
            frames = self._pipeline.wait_for_frames(self.config.frame_timeout_ms)
            if self._align is not None:
                frames = self._align.process(frames)
            color = frames.get_color_frame()
            depth = frames.get_depth_frame() if self._align is not None else None
            if not color or (self._align is not None and not depth):
                raise RuntimeError("incomplete frame set")
        except RuntimeError as error:
            return self._read_failed(str(error))
        depth_mm = None
        if depth is not None:
            raw = np.asanyarray(depth.get_data())
            depth_mm = np.clip(np.rint(raw * self._depth_scale_mm), 0, 65535).astype(np.uint16)
        self._publish(np.array(np.asanyarray(color.get_data()), copy=True), depth_mm)
        return True
