"""The seed report's block detection (../shared/seeds/002, section "D. Block Detection", in its method
and its results), as a timing reference for bench/perception.py. Not product code: it is what the
station's perception pass is measured against.

Per frame, as the report describes it:
  1. GaussianBlur 5x5, BGR -> HSV;
  2. the space mask: a rectangle around the board drawn in, a rectangle around the arm drawn out, and a
     depth threshold (minimum height half a small block);
  3. cv2.inRange per colour over the report's 6 colours (its Table IV), bitwise_and with the space mask,
     erode + dilate against noise;
  4. findContours, moments (contours of zero area dropped), drawContours on the video frame;
  5. per contour: its colour (the mean colour inside it, nearest of the course's reference colours:
     the course's retrieve_area_color, a filled contour mask over the frame and cv2.mean), its size
     (area -> big/small) and its label drawn; its centre pixel -> world through the calibration
     (depth at the centre, back-projected with K, then T_world_camera).

The student's hand-set constants (the two rectangles' pixels, the depth threshold per pixel, the area
between big and small) are derived once per calibration, in the constructor, outside the timed call.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

# Table IV of the report: HSV (OpenCV: H 0..180) lower and upper bounds per colour.
COLOR_RANGES = {
    "red": ((140, 30, 100), (180, 255, 255)),
    "orange": ((5, 50, 100), (15, 255, 255)),
    "yellow": ((20, 50, 100), (27, 255, 255)),
    "green": ((39, 50, 100), (94, 255, 255)),
    "blue": ((96, 50, 120), (130, 255, 255)),
    "violet": ((110, 50, 100), (141, 255, 255)),
}
# The course's reference colours for retrieve_area_color (BGR means inside a contour).
REFERENCE_BGR = {
    "red": (10, 10, 127), "orange": (30, 75, 150), "yellow": (30, 150, 200),
    "green": (20, 60, 20), "blue": (100, 50, 0), "violet": (100, 40, 80),
}
ARM_BOX_M = ((-0.09, 0.09), (-0.20, 0.09))  # the arm's base and its parked links (world x, y), drawn out of the space mask


@dataclass(frozen=True)
class RecipeBlock:
    color: str
    size: str
    center_px: tuple[float, float]
    position_m: np.ndarray
    yaw_deg: float


def _bounding_rect(cal, xs, ys) -> tuple[tuple[int, int], tuple[int, int]]:
    from armlab.vision.geometry import project_points

    corners = np.array([[x, y, 0.0] for x in xs for y in ys])
    px = project_points(cal.T_world_camera, cal.K, cal.dist, corners)
    lo, hi = np.floor(px.min(axis=0)).astype(int), np.ceil(px.max(axis=0)).astype(int)
    return (int(lo[0]), int(lo[1])), (int(hi[0]), int(hi[1]))


class SeedRecipe:
    """The report's detector for one calibration (cal: armlab.vision.Calibration; cfg: PerceptionConfig)."""

    def __init__(self, cal, cfg) -> None:
        self.board_rect = _bounding_rect(cal, cfg.board.x_range_m, cfg.board.y_range_m)
        self.arm_rect = _bounding_rect(cal, *ARM_BOX_M)
        # Depth threshold: the depth at which a pixel's ray is half a small block above the board.
        h, w = cal.height, cal.width
        u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        Kinv = np.linalg.inv(cal.K)
        rays = np.stack([Kinv[0, 0] * u + Kinv[0, 1] * v + Kinv[0, 2], Kinv[1, 1] * v + Kinv[1, 2], np.ones_like(u)], axis=-1)
        T = cal.T_world_depth
        along_z = rays @ T[2, :3]  # world z gained per unit of depth along each ray
        with np.errstate(divide="ignore", invalid="ignore"):
            depth_m = (0.5 * cfg.blocks.small_size_m - T[2, 3]) / along_z
        self.max_depth_mm = np.clip(np.nan_to_num(depth_m * 1000.0, nan=0.0), 0, 65535).astype(np.uint16)
        # Area between a big and a small block's top at the board's distance.
        distance_m = abs(float(T[2, 3]))
        pixel_m = distance_m / cal.K[0, 0]
        mid_m = 0.5 * (cfg.blocks.large_size_m + cfg.blocks.small_size_m)
        self.big_area_px = (mid_m / pixel_m) ** 2
        self.K_inv = Kinv
        self.T_world_camera = T
        self.kernel = np.ones((3, 3), np.uint8)
        self.references = {name: np.array(bgr, np.float64) for name, bgr in REFERENCE_BGR.items()}

    def retrieve_area_color(self, frame_bgr: np.ndarray, contour: np.ndarray) -> str:
        """The course's: the mean colour inside the contour, named by the nearest reference colour."""
        mask = np.zeros(frame_bgr.shape[:2], np.uint8)
        cv2.drawContours(mask, [contour], -1, 255, -1)
        mean = np.array(cv2.mean(frame_bgr, mask=mask)[:3])
        return min(self.references, key=lambda name: np.linalg.norm(self.references[name] - mean))

    def detect(self, color_bgr: np.ndarray, depth_mm: np.ndarray) -> tuple[list[RecipeBlock], np.ndarray]:
        """Blocks and the video frame with their contours and labels drawn."""
        blur = cv2.GaussianBlur(color_bgr, (5, 5), 0)
        hsv = cv2.cvtColor(blur, cv2.COLOR_BGR2HSV)
        space = np.zeros(color_bgr.shape[:2], np.uint8)
        cv2.rectangle(space, *self.board_rect, 255, -1)
        cv2.rectangle(space, *self.arm_rect, 0, -1)
        raised = cv2.bitwise_and(cv2.compare(depth_mm, 0, cv2.CMP_GT), cv2.compare(depth_mm, self.max_depth_mm, cv2.CMP_LT))
        space = cv2.bitwise_and(space, raised)
        frame = color_bgr.copy()
        blocks: list[RecipeBlock] = []
        for lo, hi in COLOR_RANGES.values():
            mask = cv2.bitwise_and(cv2.inRange(hsv, lo, hi), space)
            mask = cv2.dilate(cv2.erode(mask, self.kernel), self.kernel)
            contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            kept = []
            for contour in contours:
                M = cv2.moments(contour)
                if M["m00"] == 0:
                    continue  # a single point or a line: noise
                kept.append((contour, M))
            cv2.drawContours(frame, [c for c, _ in kept], -1, (0, 255, 255), 2)
            for contour, M in kept:
                cx, cy = M["m10"] / M["m00"], M["m01"] / M["m00"]
                color = self.retrieve_area_color(color_bgr, contour)
                size = "big" if M["m00"] >= self.big_area_px else "small"
                yaw_deg = cv2.minAreaRect(contour)[2]
                u, v = int(round(cx)), int(round(cy))
                z_m = float(depth_mm[v, u]) / 1000.0
                p_cam = z_m * (self.K_inv @ np.array([cx, cy, 1.0]))
                position = self.T_world_camera[:3, :3] @ p_cam + self.T_world_camera[:3, 3]
                cv2.putText(frame, f"{color} {size}", (u - 30, v + 30), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
                cv2.putText(frame, f"{int(yaw_deg)}", (u, v), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1)
                blocks.append(RecipeBlock(color, size, (cx, cy), position, yaw_deg))
        return blocks, frame
