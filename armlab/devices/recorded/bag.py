"""A ROS 2 bag (or ROS 1 .bag) with colour, depth aligned to colour and camera_info topics, read with `rosbags`.

Topics are named in the config or found by name: depth = the one image topic with "aligned" and "depth" in
its name (else the only one with "depth"); colour = the image topic with "color" (else "rgb") that is not
depth; camera_info = the CameraInfo beside the colour topic (else the only one). Colour and depth are paired
by header stamp (within max_skew_s). Images: sensor_msgs Image (rgb8, bgr8, rgba8, bgra8, mono8; depth 16UC1 or
mono16 in mm, 32FC1 in metres) or CompressedImage (colour JPEG/PNG; depth compressedDepth PNG).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from functools import partial
from pathlib import Path

import cv2
import numpy as np

from armlab.devices.camera import Intrinsics
from armlab.devices.recorded.folder import RecordingError

IMAGE_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")
INFO_TYPE = "sensor_msgs/msg/CameraInfo"


def _stamp_s(message) -> float:
    stamp = message.header.stamp
    return float(stamp.sec) + float(getattr(stamp, "nanosec", getattr(stamp, "nsec", 0))) * 1e-9


def _pick(candidates: list[str], preferred: tuple[str, ...], what: str, bag: Path, all_topics: list[str]) -> str:
    for words in preferred:
        chosen = [t for t in candidates if all(w in t.lower() for w in words.split("+"))]
        if len(chosen) == 1:
            return chosen[0]
        if len(chosen) > 1:
            raise RecordingError(f"{bag}: several {what} topics ({', '.join(chosen)}): name one in the camera config")
    raise RecordingError(f"{bag}: no {what} topic found (topics: {', '.join(all_topics) or 'none'}); name one in the camera config")


def decode_image(message, msgtype: str, depth: bool, where: str) -> np.ndarray:
    """(H, W, 3) uint8 BGR colour, or (H, W) uint16 mm depth, from an Image or CompressedImage message."""
    data = np.frombuffer(bytes(message.data), dtype=np.uint8)
    if msgtype.endswith("CompressedImage"):
        if depth and "compresseddepth" in str(message.format).lower():
            data = data[12:]  # compressed_depth_image_transport's header before the PNG
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED if depth else cv2.IMREAD_COLOR)
        if image is None:
            raise RecordingError(f"{where}: cannot decode the compressed image ({message.format})")
        if depth and image.dtype != np.uint16:
            raise RecordingError(f"{where}: compressed depth must decode to 16-bit millimetres, got {image.dtype}")
        return image
    height, width, step, encoding = int(message.height), int(message.width), int(message.step), str(message.encoding).lower()
    channels = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1, "8uc1": 1, "8uc3": 3, "16uc1": 2, "mono16": 2, "32fc1": 4}
    if encoding not in channels or (depth != (encoding in ("16uc1", "mono16", "32fc1"))):
        kind = "depth (16UC1, mono16 or 32FC1)" if depth else "colour (rgb8, bgr8, rgba8, bgra8, mono8)"
        raise RecordingError(f"{where}: encoding '{message.encoding}' is not {kind}")
    row_bytes = width * channels[encoding]
    if step < row_bytes or data.size < step * height:
        raise RecordingError(f"{where}: {data.size} bytes do not hold {width}x{height} {message.encoding} (step {step})")
    rows = data[: step * height].reshape(height, step)[:, :row_bytes]
    if depth:
        if encoding == "32fc1":
            metres = rows.copy().view("<f4" if not message.is_bigendian else ">f4").reshape(height, width)
            return np.where(np.isfinite(metres) & (metres > 0), np.round(metres * 1000.0), 0).astype(np.uint16)
        return rows.copy().view("<u2" if not message.is_bigendian else ">u2").reshape(height, width).astype(np.uint16)
    image = rows.reshape(height, width, -1)
    conversion = {"rgb8": cv2.COLOR_RGB2BGR, "rgba8": cv2.COLOR_RGBA2BGR, "bgra8": cv2.COLOR_BGRA2BGR, "mono8": cv2.COLOR_GRAY2BGR,
                  "8uc1": cv2.COLOR_GRAY2BGR}.get(encoding)
    return np.ascontiguousarray(image if conversion is None else cv2.cvtColor(image, conversion))


class BagRecording:
    """An open bag: the chosen topics, intrinsics from camera_info, and colour/depth pairs in time order."""

    def __init__(self, path: Path, color_topic: str | None = None, depth_topic: str | None = None, info_topic: str | None = None,
                 max_skew_s: float = 0.02) -> None:
        from rosbags.highlevel import AnyReader
        from rosbags.typesys import Stores, get_typestore

        self.path = Path(path)
        self.max_skew_s = max_skew_s
        bag_paths = [self.path]
        try:
            self._reader = AnyReader(bag_paths, default_typestore=get_typestore(Stores.ROS2_HUMBLE))
            self._reader.open()
        except Exception as error:  # noqa: BLE001 - rosbags raises several types for a damaged bag; all mean "unreadable"
            raise RecordingError(f"{self.path}: not a readable ROS bag: {type(error).__name__}: {error}") from error
        try:
            self._choose_topics(color_topic, depth_topic, info_topic)
        except BaseException:
            self.close()
            raise

    def _choose_topics(self, color_topic, depth_topic, info_topic) -> None:
        connections = self._reader.connections
        types = {c.topic: c.msgtype for c in connections}
        topics = sorted(types)
        images = [t for t in topics if types[t] in IMAGE_TYPES]
        infos = [t for t in topics if types[t] == INFO_TYPE]
        for name, given, allowed in (("color_topic", color_topic, images), ("depth_topic", depth_topic, images), ("info_topic", info_topic, infos)):
            if given is not None and given not in allowed:
                raise RecordingError(f"{self.path}: {name} '{given}' is not an image/camera_info topic of the bag (topics: {', '.join(topics)})")
        self.depth_topic = depth_topic or _pick([t for t in images if "depth" in t.lower()], ("aligned+depth", "depth"), "aligned depth", self.path, topics)
        self.color_topic = color_topic or _pick([t for t in images if t != self.depth_topic and "depth" not in t.lower()],
                                                ("color+image_raw", "color", "rgb", "image"), "colour", self.path, topics)
        if info_topic is None and infos:
            beside = self.color_topic.rsplit("/", 1)[0] + "/camera_info"
            info_topic = beside if beside in infos else (infos[0] if len(infos) == 1 else None)
        self.info_topic = info_topic
        self.types = types
        self._connections = [c for c in connections if c.topic in (self.color_topic, self.depth_topic)]
        self._info_connections = [c for c in connections if c.topic == self.info_topic]

    def close(self) -> None:
        try:
            self._reader.close()
        except Exception:  # noqa: BLE001 - closing twice or after a failed open
            pass

    def _deserialize(self, connection, rawdata):
        try:
            return self._reader.deserialize(rawdata, connection.msgtype)
        except Exception as error:  # noqa: BLE001 - a damaged message: name it
            raise RecordingError(f"{self.path}: {connection.topic}: cannot deserialize a message: {error}") from error

    def intrinsics(self) -> Intrinsics | None:
        """From the first camera_info message (None without a camera_info topic)."""
        if not self._info_connections:
            return None
        try:
            for connection, _, rawdata in self._reader.messages(connections=self._info_connections):
                info = self._deserialize(connection, rawdata)
                K = np.asarray(info.k, dtype=float).reshape(3, 3)
                if not (np.all(np.isfinite(K)) and K[0, 0] > 0 and K[1, 1] > 0):
                    raise RecordingError(f"{self.path}: {self.info_topic}: camera_info has no usable K ({K.ravel().tolist()})")
                dist = tuple(float(v) for v in info.d) or (0.0,) * 5
                return Intrinsics(int(info.width), int(info.height), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), dist)
        except RecordingError:
            raise
        except Exception as error:  # noqa: BLE001 - damaged storage
            raise RecordingError(f"{self.path}: cannot read {self.info_topic}: {type(error).__name__}: {error}") from error
        return None

    def pairs(self) -> Iterator[tuple[float, Callable[[], tuple[np.ndarray, np.ndarray]]]]:
        """(colour stamp in s, decode) for each colour message with a depth message within max_skew_s; decode()
        gives (colour BGR, depth mm), so pairs that are skipped are never decoded."""
        color = depth = None  # (stamp, connection, message) not yet paired
        try:
            for connection, _, rawdata in self._reader.messages(connections=self._connections):
                message = self._deserialize(connection, rawdata)
                entry = (_stamp_s(message), connection, message)
                if connection.topic == self.color_topic:
                    color = entry
                else:
                    depth = entry
                if color is not None and depth is not None and abs(color[0] - depth[0]) <= self.max_skew_s:
                    yield color[0], partial(self._decode_pair, color, depth)
                    color = depth = None
        except RecordingError:
            raise
        except Exception as error:  # noqa: BLE001 - damaged storage part-way through
            raise RecordingError(f"{self.path}: cannot read messages: {type(error).__name__}: {error}") from error

    def _decode_pair(self, color, depth) -> tuple[np.ndarray, np.ndarray]:
        return self._decode(color, False), self._decode(depth, True)

    def _decode(self, entry, depth: bool) -> np.ndarray:
        stamp, connection, message = entry
        return decode_image(message, connection.msgtype, depth, f"{self.path}: {connection.topic} at {stamp:.3f} s")
