"""Composing the streamed image for a view (colour, depth, top-down) with overlay layers, and JPEG encoding."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from armlab.devices.camera import Frame
from armlab.vision import OverlayLayers, draw_overlay, top_down_view

VIEWS = ("color", "depth", "topdown")
LAYERS = ("tags", "detections", "grid")


@dataclass(frozen=True)
class ViewKey:
    """What a client watches: the view and the overlay layers drawn into it (sorted, so keys compare)."""

    view: str = "color"
    layers: tuple[str, ...] = ()

    @classmethod
    def make(cls, view: str = "color", layers=()) -> ViewKey:
        if view not in VIEWS:
            raise ValueError(f"view must be one of {', '.join(VIEWS)}, not {view!r}")
        unknown = [layer for layer in layers if layer not in LAYERS]
        if unknown:
            raise ValueError(f"unknown layers {unknown}; known: {', '.join(LAYERS)}")
        return cls(view, tuple(sorted(set(layers))))

    @classmethod
    def parse(cls, view: str | None, layers: str | None) -> ViewKey:
        """From query strings: view=color, layers=tags,detections,grid."""
        names = [name.strip() for name in (layers or "").split(",") if name.strip()]
        return cls.make(view or "color", names)


def depth_to_bgr(depth_mm: np.ndarray, scale_bar: bool = True) -> np.ndarray:
    """A colour-mapped depth image (near = warm); no reading = black; with a colour scale (mm) at the right edge."""
    valid = depth_mm > 0
    if not np.any(valid):
        return np.zeros((*depth_mm.shape, 3), np.uint8)
    near, far = np.percentile(depth_mm[valid], (1, 99))
    scaled = np.clip((far - depth_mm.astype(np.float32)) / max(far - near, 1.0), 0.0, 1.0)
    image = cv2.applyColorMap((scaled * 255).astype(np.uint8), cv2.COLORMAP_TURBO)
    image[~valid] = 0
    if scale_bar:
        draw_depth_scale(image, float(near), float(far))
    return image


def draw_depth_scale(image: np.ndarray, near_mm: float, far_mm: float) -> None:
    """A vertical colour bar at the right edge, near (warm, top) to far (cold, bottom), labelled in mm."""
    h, w = image.shape[:2]
    bar_w, margin = max(12, w // 64), max(8, h // 40)
    top, bottom = margin + 24, h - margin - 24
    if bottom - top < 20:
        return
    ramp = np.linspace(255, 0, bottom - top).astype(np.uint8)[:, None]
    bar = cv2.applyColorMap(np.repeat(ramp, bar_w, axis=1), cv2.COLORMAP_TURBO)
    x0 = w - margin - bar_w
    image[top:bottom, x0 : x0 + bar_w] = bar
    cv2.rectangle(image, (x0 - 1, top - 1), (x0 + bar_w, bottom), (255, 255, 255), 1)
    font, scale = cv2.FONT_HERSHEY_SIMPLEX, max(0.45, h / 1200)
    for text, y in ((f"{near_mm:.0f} mm", top - 8), (f"{far_mm:.0f} mm", bottom + 18)):
        (tw, _), _ = cv2.getTextSize(text, font, scale, 1)
        origin = (w - margin - tw, y)
        cv2.putText(image, text, origin, font, scale, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(image, text, origin, font, scale, (255, 255, 255), 1, cv2.LINE_AA)


def compose_view(frame: Frame, key: ViewKey, perception=None, calibration=None, config=None) -> np.ndarray:
    """The BGR image of `key` for `frame`: base image (colour, depth map or top-down warp) + overlays.

    Top-down needs a calibration (else the colour image is shown); overlays are drawn on colour and
    depth (same pixel grid) and skipped on the top-down warp.
    """
    if key.view == "depth" and frame.depth_mm is not None:
        image = depth_to_bgr(frame.depth_mm)
    elif key.view == "topdown" and calibration is not None:
        return top_down_view(frame.color_bgr, calibration)
    else:
        image = frame.color_bgr
    if not key.layers:
        return image

    layers = OverlayLayers(**{name: name in key.layers for name in LAYERS})
    tags = list(perception.tags) if perception is not None else []
    blocks = list(perception.blocks) if perception is not None else []
    return draw_overlay(image, tags=tags, blocks=blocks, calibration=calibration, layers=layers)


def encode_jpeg(image: np.ndarray, quality: int) -> bytes:
    ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:
        raise ValueError("JPEG encoding failed")
    return data.tobytes()
