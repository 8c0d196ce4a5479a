"""The real L515's imperfections on a clean render (`realism: real`): the depth's board plane offset and
tilted against the true board, depth noise growing with range, holes and flying pixels at depth edges,
holes on dark faces, a side band without depth, and drifting white balance and exposure. Magnitudes:
config/cameras/<name>.yaml `realism:` (measured on real frames by bench/real_camera.py).

Random draws come from seeded banks shifted per frame (nothing is generated on the hot path); the
drift is a function of simulated time, so a seed and a sequence of calls give the same frames."""

from __future__ import annotations

import math

import cv2
import numpy as np

from armlab.devices.sim.config import CameraRealismConfig, SimCameraConfig

BANK_SIZE = 3


def _tiled(image: np.ndarray) -> np.ndarray:
    """An (H, W) image tiled two by two, read-only: its (H, W) window at (top, left) is the image rolled by
    (H - top, W - left) rows and columns."""
    tiled = np.tile(image, (2, 2))
    tiled.flags.writeable = False
    return tiled


class RealCamera:
    """Applies CameraRealismConfig to renders of one camera (its true intrinsics, no distortion)."""

    def __init__(self, camera: SimCameraConfig, realism: CameraRealismConfig, rng: np.random.Generator,
                 depth_noise: bool) -> None:
        self.config = realism
        self._rng = rng
        height, width = camera.height, camera.width
        k = camera.intrinsics
        # Each pixel's ray (x, y, 1) in the camera frame: the offset and tilt maps are made from them.
        self._ray_x, self._ray_y = np.meshgrid((np.arange(width, dtype=np.float32) - k.cx) / k.fx,
                                               (np.arange(height, dtype=np.float32) - k.cy) / k.fy)
        self._slope = math.tan(math.radians(realism.depth_tilt_deg))
        self._depth_gain = None  # depth change = Z * gain + shift (maps), set by set_board()
        self._depth_shift = None
        self._gauss = ([_tiled(rng.standard_normal((height, width)).astype(np.float32)) for _ in range(BANK_SIZE)]
                       if depth_noise and realism.noise_std_at_1m_mm > 0 else [])
        self._uniform = [_tiled(rng.random((height, width), dtype=np.float32)) for _ in range(BANK_SIZE)]
        self._shape = (height, width)
        self._phases = rng.uniform(0.0, 2.0 * math.pi, size=4)
        self._band_kernel = np.ones((2 * realism.edge_band_px + 1,) * 2, np.uint8)
        left, right = realism.no_depth_columns
        self._no_depth = (slice(0, left), slice(width - right, width) if right else slice(0, 0))

    def set_board(self, T_world_camera: np.ndarray, pivot_m) -> None:
        """Place the depth's board plane against the true board as this camera sees it (call again when the
        camera moves): every point moves along its ray so that the board's points rise off the board by
        offset + tan(tilt) * (distance from the pivot, the board tags' centre, along the tilt's direction),
        measured along the board's normal (+ toward the camera). The board the depth shows is then exactly
        that offset and tilt away, as calibration measures them (armlab.vision.board_plane)."""
        cfg = self.config
        R, t = T_world_camera[:3, :3], T_world_camera[:3, 3]
        centre_mm = 1000.0 * (R.T @ (np.array([pivot_m[0], pivot_m[1], 0.0]) - t))
        normal = R.T @ np.array([0.0, 0.0, 1.0])  # the board's normal in the camera frame
        axis = math.radians(cfg.depth_tilt_axis_deg)  # the tilt's axis in the board; it slopes across it
        slope_dir = R.T @ np.array([-math.sin(axis), math.cos(axis), 0.0])
        # A step dz along a pixel's ray moves its point by dz * |n . r| along the board's normal, away from the camera.
        per_normal = 1.0 / np.abs(normal[0] * self._ray_x + normal[1] * self._ray_y + normal[2])
        along = slope_dir[0] * self._ray_x + slope_dir[1] * self._ray_y + slope_dir[2]  # (slope_dir . P) / Z
        self._depth_gain = (-self._slope * along * per_normal).astype(np.float32)
        shift_mm = -(1000.0 * cfg.depth_offset_m - self._slope * float(slope_dir @ centre_mm))
        self._depth_shift = (shift_mm * per_normal).astype(np.float32)

    def with_depth(self, offset_m: float | None, tilt_deg: float | None) -> None:
        """Replace the configured offset and/or tilt (before set_board)."""
        updates = {k: v for k, v in (("depth_offset_m", offset_m), ("depth_tilt_deg", tilt_deg)) if v is not None}
        if updates:
            self.config = self.config.model_copy(update=updates)
            self._slope = math.tan(math.radians(self.config.depth_tilt_deg))

    def _bank(self, bank: list[np.ndarray]) -> np.ndarray:
        """A bank image rolled by a random number of rows and columns (np.roll's values), as a read-only window of
        its tiled copy: no image-sized copy per draw."""
        height, width = self._shape
        image = bank[int(self._rng.integers(len(bank)))]
        rows, columns = int(self._rng.integers(height)), int(self._rng.integers(width))
        top, left = (height - rows) % height, (width - columns) % width
        return image[top:top + height, left:left + width]

    def color_gains(self, sim_time_s: float) -> tuple[float, float, float]:
        """The (R, G, B) gains at a simulated time: white balance and exposure, each drifting slowly."""
        cfg = self.config
        phase = 2.0 * math.pi * sim_time_s / cfg.drift_period_s
        exposure = 1.0 + cfg.exposure_drift * math.sin(0.61 * phase + self._phases[3])  # its own, slower period
        return tuple(float(g * (1.0 + d * math.sin(phase + p)) * exposure)
                     for g, d, p in zip(cfg.white_balance_gains, cfg.white_balance_drift, self._phases[:3]))

    def color(self, rgb: np.ndarray, sim_time_s: float) -> np.ndarray:
        """rgb (H, W, 3) uint8 with the drifting gains at sim_time_s, rounded and saturated, through a per-channel
        table (the same pixels as multiplying each one, a quarter of the CPU)."""
        if rgb.shape[2] != 3:
            return rgb
        gains = np.array(self.color_gains(sim_time_s))
        table = np.clip(np.rint(np.arange(256.0)[:, None] * gains), 0, 255).astype(np.uint8).reshape(256, 1, 3)
        return cv2.LUT(rgb, table)

    def depth(self, depth_mm: np.ndarray, rgb: np.ndarray) -> np.ndarray:
        """depth_mm (float32, mm along the optical axis) with the imperfections; 0 where no reading."""
        cfg = self.config
        if self._depth_gain is not None:  # offset and tilt (set_board): Z' = Z + Z * gain + shift
            depth_mm = cv2.add(cv2.addWeighted(depth_mm, 1.0, cv2.multiply(depth_mm, self._depth_gain), 1.0, 0.0),
                               self._depth_shift)
        # Edges: within edge_band_px of a step, some pixels read nothing, some a depth between the sides.
        near = cv2.erode(depth_mm, self._band_kernel)
        far = cv2.dilate(depth_mm, self._band_kernel)
        step = far - near
        edge = step > cfg.edge_step_mm
        draw = self._bank(self._uniform)
        out = depth_mm.copy()
        flying = edge & (draw < cfg.edge_flying_fraction)
        mix = self._bank(self._uniform)
        out[flying] = near[flying] + mix[flying] * step[flying]
        out[edge & (draw >= cfg.edge_flying_fraction) & (draw < cfg.edge_flying_fraction + cfg.edge_hole_fraction)] = 0.0
        if self._gauss:  # noise growing with range: std = std_1m * (Z / 1 m) ** exponent
            scale = out * np.float32(0.001)
            if cfg.noise_range_exponent != 1.0:
                scale = cv2.pow(scale, cfg.noise_range_exponent)
            out = cv2.addWeighted(out, 1.0, cv2.multiply(self._bank(self._gauss), scale, scale=cfg.noise_std_at_1m_mm), 1.0, 0.0)
        # Dark faces return too little light: a fraction reads nothing.
        if cfg.dark_hole_fraction > 0:
            grey = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY)
            out[(grey < cfg.dark_level) & (self._bank(self._uniform) < cfg.dark_hole_fraction)] = 0.0
        for columns in self._no_depth:
            out[:, columns] = 0.0
        return out
