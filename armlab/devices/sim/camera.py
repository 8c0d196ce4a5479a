"""SimCamera: the Camera interface over the workcell's renderer, with L515-like colour and depth noise.

It sees only pixels: the true camera pose and object poses stay in SimWorkcell.truth(). Noise is drawn
from a seeded bank of precomputed noise images (cheap per frame, reproducible for a seed)."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

import cv2
import numpy as np

from armlab.devices.camera import Camera, Frame, Intrinsics
from armlab.devices.sim.config import SimCameraConfig
from armlab.devices.sim.device import SimDevice
from armlab.devices.sim.realism import RealCamera
from armlab.devices.sim.render import RawImages

if TYPE_CHECKING:
    from armlab.devices.sim.workcell import SimWorkcell

NOISE_BANK_SIZE = 3


class NoiseModel:
    """Turns a clean render into a camera frame: colour noise (Gaussian, per channel) and depth noise
    (Gaussian in mm, random dropouts, no reading outside the range). Per frame it adds a bank image
    shifted by a random number of rows, so no noise is generated on the hot path. real: the real camera's
    imperfections (armlab.devices.sim.realism) replace the flat depth noise; None: the ideal camera."""

    def __init__(self, config: SimCameraConfig, rng: np.random.Generator, color_noise: bool, depth_noise: bool,
                 real: RealCamera | None = None) -> None:
        self._config = config
        self._rng = rng
        self.real = real
        shape = (config.height, config.width)
        self._pixels = config.height * config.width
        self._color_bank: list[np.ndarray] = []
        self._depth_bank: list[np.ndarray] = []
        self._dropout_bank: list[np.ndarray] = []
        if color_noise and config.color.noise_std > 0:
            self._color_bank = [
                np.clip(np.rint(rng.normal(0.0, config.color.noise_std, (*shape, 3))), -127, 127).astype(np.int16)
                for _ in range(NOISE_BANK_SIZE)
            ]
        if depth_noise and real is None:
            self._depth_bank = [
                rng.normal(0.0, config.depth.noise_std_mm, shape).astype(np.float32) for _ in range(NOISE_BANK_SIZE)
            ]
            count = int(round(config.depth.dropout_fraction * self._pixels))
            self._dropout_bank = [rng.choice(self._pixels, size=count, replace=False) for _ in range(NOISE_BANK_SIZE)]

    def _shift(self) -> tuple[int, int]:
        return int(self._rng.integers(NOISE_BANK_SIZE)), int(self._rng.integers(self._config.height))

    @staticmethod
    def _add_rolled(image: np.ndarray, noise: np.ndarray, rows: int, out: np.ndarray, dtype: int) -> None:
        """out = image + noise rolled down by `rows` (saturating), without materialising the roll."""
        height = image.shape[0]
        cv2.add(image[rows:], noise[: height - rows], dst=out[rows:], dtype=dtype)
        if rows:
            cv2.add(image[:rows], noise[height - rows :], dst=out[:rows], dtype=dtype)

    def apply(self, images: RawImages) -> tuple[np.ndarray, np.ndarray]:
        """(color_bgr uint8, depth_mm uint16) from a render."""
        rgb = images.rgb
        if self.real is not None:
            rgb = self.real.color(rgb, images.sim_time_s)
        if self._color_bank:
            index, rows = self._shift()
            noisy = np.empty_like(rgb)
            self._add_rolled(rgb, self._color_bank[index], rows, noisy, cv2.CV_8U)
            rgb = noisy
        color_bgr = cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)
        depth_m = images.depth_m
        depth_mm = cv2.addWeighted(depth_m, 1000.0, depth_m, 0.0, 0.5)  # +0.5: truncation below rounds
        if self._depth_bank:
            index, rows = self._shift()
            self._add_rolled(depth_mm, self._depth_bank[index], rows, depth_mm, cv2.CV_32F)
        if self.real is not None:
            depth_mm = self.real.depth(depth_mm, images.rgb)
        depth_cfg = self._config.depth
        valid = cv2.inRange(depth_m, depth_cfg.min_range_m, depth_cfg.max_range_m)
        out = depth_mm.astype(np.uint16)
        out = cv2.bitwise_and(out, out, mask=valid)  # no reading outside the range
        if self._dropout_bank:
            index, rows = self._shift()
            out.flat[(self._dropout_bank[index] + rows * self._config.width) % self._pixels] = 0
        return color_bgr, out


class SimCamera(SimDevice, Camera):
    """The workcell's overhead RGB-D camera. In fast mode read()/async_read() advance the physics to the
    next frame time and render; in real time a render thread publishes frames at the camera rate."""

    def __init__(self, cell: SimWorkcell, config: SimCameraConfig, noise: NoiseModel, fps: float) -> None:
        self._cell = cell
        self._config = config
        self._noise = noise
        self._fps = fps
        self._intrinsics = config.to_intrinsics()
        self._condition = threading.Condition()
        self._latest: Frame | None = None
        self._sequence = 0
        self._last_async_sequence = 0

    def __str__(self) -> str:
        return f"SimCamera({self._config.name})"

    @property
    def fps(self) -> float:
        return self._fps

    @property
    def intrinsics(self) -> Intrinsics:
        return self._intrinsics

    def close(self) -> None:
        super().close()
        with self._condition:
            self._condition.notify_all()  # a reader waiting for a frame sees the camera closed

    def set_board(self, T_world_camera: np.ndarray, pivot_m) -> None:
        """Tell the realistic depth where the board is seen (its offset and tilt pivot at pivot_m); no-op if ideal."""
        if self._noise.real is not None:
            self._noise.real.set_board(T_world_camera, pivot_m)

    def publish(self, images: RawImages) -> Frame:
        """Add noise, stamp and store a render as the newest frame (called by the workcell)."""
        color_bgr, depth_mm = self._noise.apply(images)
        with self._condition:
            self._sequence += 1
            captured_s = images.wall_time_s if images.wall_time_s is not None else time.time()  # the state's time, not the drawing's
            frame = Frame(color_bgr=color_bgr, depth_mm=depth_mm, timestamp_s=captured_s,
                          sequence=self._sequence, intrinsics=self._intrinsics, arm_joints_rad=images.arm_joints_rad,
                          gripper_closed=images.gripper_closed)
            self._latest = frame
            self._condition.notify_all()
        return frame

    def _wait_for(self, after_sequence: int, timeout_s: float | None) -> Frame:
        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        with self._condition:
            while self._latest is None or self._latest.sequence <= after_sequence:
                self._require()
                remaining = None if deadline is None else deadline - time.monotonic()
                if remaining is not None and remaining <= 0:
                    raise TimeoutError(f"{self}: no new frame within {timeout_s * 1000:.0f} ms")
                self._condition.wait(remaining if remaining is not None else 1.0)
            return self._latest

    def read(self) -> Frame:
        self._require()
        if not self._cell.realtime:
            return self._cell.capture_next_frame()
        with self._condition:
            current = self._sequence
        return self._wait_for(current, timeout_s=max(2.0, 20.0 / self._fps))

    def async_read(self, timeout_ms: float = 200.0) -> Frame:
        self._require()
        if not self._cell.realtime:
            frame = self._cell.capture_next_frame()
        else:
            frame = self._wait_for(self._last_async_sequence, timeout_s=timeout_ms / 1000.0)
        self._last_async_sequence = frame.sequence
        return frame

    def read_latest(self, max_age_ms: float = 500.0) -> Frame:
        self._require()
        with self._condition:
            frame = self._latest
        if frame is not None and (time.time() - frame.timestamp_s) * 1000.0 <= max_age_ms:
            return frame
        if not self._cell.realtime:
            return self._cell.render()
        if frame is None:
            raise TimeoutError(f"{self}: no frame yet")
        raise TimeoutError(f"{self}: newest frame is {(time.time() - frame.timestamp_s) * 1000:.0f} ms old (> {max_age_ms} ms)")
