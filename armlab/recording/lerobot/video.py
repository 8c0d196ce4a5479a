"""The camera of a LeRobot export as one MP4 per camera (PyAV), as LeRobot encodes its own datasets.

LeRobot's defaults (lerobot/datasets/video_utils.py, encode_video_frames): AV1 by SVT-AV1 ("libsvtav1"), pix_fmt
yuv420p, a key frame every 2 frames (g=2, so any frame decodes fast), crf 30, preset 12. Episodes follow one another
in the file: frame k of the file is at k / fps (its pts), and an episode's frames run from its from_timestamp.
H.264 (libx264) when the PyAV build has no SVT-AV1. yuv420p needs even sizes: an odd last row or column is dropped.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from armlab.errors import RefusedByCheck
from armlab.recording.lerobot.episode import ExportRefused
from armlab.recording.lerobot.fair_threads import FairThreads

CODECS = ("libsvtav1", "libx264")  # preferred first; LeRobot decodes both (torchcodec or PyAV)
PIX_FMT = "yuv420p"
STATS_FRAMES_PER_EPISODE = 100  # colour statistics from at most this many frames per episode, evenly spaced
STATS_EDGE_PX = 150  # ... each shrunk to about this many pixels on its longer side (as LeRobot samples images)


class ExtraMissing(RefusedByCheck):
    """An optional package the LeRobot export needs is not installed (pip install 'armlab[lerobot]')."""


def require(module: str):
    """Import an optional package of the `lerobot` extra, or ExtraMissing naming it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as error:
        raise ExtraMissing(f"the LeRobot export needs {module.split('.')[0]} ({error}): pip install 'armlab[lerobot]'") from None


def pick_codec(requested: str | None = None) -> str:
    av = require("av")
    for codec in [requested] if requested else CODECS:
        try:
            av.codec.Codec(codec, "w")
            return codec
        except Exception:  # noqa: BLE001 - PyAV raises UnknownCodecError (its own class) for a missing encoder
            continue
    raise ExtraMissing(f"this PyAV build has no {' or '.join([requested] if requested else CODECS)} encoder")


def decode_jpeg(jpeg: bytes) -> np.ndarray:
    """A recorded colour frame as RGB (H, W, 3) uint8."""
    bgr = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    if bgr is None:
        raise ExportRefused("a recorded colour frame does not decode as an image")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def even_size(width: int, height: int) -> tuple[int, int]:
    return width - width % 2, height - height % 2


@dataclass
class EncodedVideo:
    width: int
    height: int
    frames: int
    codec: str
    episode_samples: list[np.ndarray]  # per episode: sampled frames (S, 3, h, w) float32 in [0, 1] for the stats


def encode(path: Path, episodes: Iterable[tuple[Sequence[bytes], np.ndarray]], fps: int, size: tuple[int, int],
           codec: str | None = None) -> EncodedVideo:
    """Write `path`: per episode, (its JPEG frames, the frame index shown at each of its frames). size: (width, height)
    of every frame (even). Returns the size, frame count, codec, and each episode's sampled frames."""
    av = require("av")
    codec = pick_codec(codec)
    width, height = size
    options = {"g": "2", "crf": "30"}
    if codec == "libsvtav1":
        options["preset"] = "12"
    samples: list[np.ndarray] = []
    written = 0
    # SVT-AV1 as root makes the feeding thread and its workers SCHED_FIFO 99 (fair_threads): undone after each call.
    with FairThreads() as fair, av.open(str(path), "w", format="mp4") as container:
        stream = container.add_stream(codec, rate=fps, options=options)
        stream.pix_fmt, stream.width, stream.height = PIX_FMT, width, height
        for jpegs, shown in episodes:
            picks = set(np.linspace(0, len(shown) - 1, min(len(shown), STATS_FRAMES_PER_EPISODE)).round().astype(int).tolist())
            sampled = []
            last_index, pixels = None, np.zeros((height, width, 3), np.uint8)
            for k, index in enumerate(shown):
                if index != last_index:  # a colour frame shown at several frames (a camera slower than fps) decodes once
                    rgb = decode_jpeg(jpegs[int(index)])
                    if rgb.shape[1] < width or rgb.shape[0] < height:
                        raise ExportRefused(f"a colour frame of {rgb.shape[1]}x{rgb.shape[0]} px in a video of {width}x{height}")
                    pixels, last_index = np.ascontiguousarray(rgb[:height, :width]), index
                frame = av.VideoFrame.from_ndarray(pixels, format="rgb24")
                frame.pts = written
                for packet in stream.encode(frame):
                    container.mux(packet)
                fair.restore()
                written += 1
                if k in picks:
                    sampled.append(_shrunk(pixels))
            samples.append(np.stack(sampled))
        for packet in stream.encode():
            container.mux(packet)
    return EncodedVideo(width, height, written, codec, samples)


def _shrunk(rgb: np.ndarray) -> np.ndarray:
    """(3, h, w) float32 in [0, 1], the longer side about STATS_EDGE_PX (LeRobot's auto_downsample_height_width)."""
    step = max(1, max(rgb.shape[:2]) // STATS_EDGE_PX)
    return (rgb[::step, ::step].transpose(2, 0, 1).astype(np.float32)) / 255.0


def video_info(path: Path) -> dict:
    """The `info` of a video feature in meta/info.json, read back from the file as LeRobot's get_video_info does."""
    av = require("av")
    with av.open(str(path), "r") as container:
        stream = container.streams.video[0]
        has_audio = bool(container.streams.audio)
        return {
            "video.height": int(stream.height), "video.width": int(stream.width), "video.codec": stream.codec.canonical_name,
            "video.pix_fmt": stream.pix_fmt, "video.is_depth_map": False, "video.fps": int(stream.base_rate),
            "video.channels": 3, "has_audio": has_audio,
        }
