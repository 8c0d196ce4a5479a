"""Small recordings written by the tests: a folder of image_<name>.png + depth_<name>.png pairs with an
intrinsics.json, and a ROS 2 bag (written with rosbags itself) with colour, aligned depth and camera_info."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

K_TEST = [[100.0, 0.0, 31.5], [0.0, 101.0, 23.5], [0.0, 0.0, 1.0]]
DIST_TEST = [0.01, -0.02, 0.0, 0.0, 0.003]


def pair_images(index: int, size=(64, 48)) -> tuple[np.ndarray, np.ndarray]:
    """Colour (BGR, distinct channels, a level per index) and 16-bit depth (mm, a gradient + index)."""
    width, height = size
    color = np.zeros((height, width, 3), np.uint8)
    color[..., 0] = 20 + 40 * index
    color[..., 1] = 200 - 30 * index
    color[..., 2] = np.arange(width, dtype=np.uint8)[None, :]
    depth = (900 + 10 * index + np.arange(height, dtype=np.uint16)[:, None] + np.zeros((1, width), np.uint16)).astype(np.uint16)
    return color, depth


def write_pairs(folder: Path, names=("a", "b"), size=(64, 48), intrinsics=True) -> Path:
    """The pairs (image_<name>.png, depth_<name>.png) and, unless intrinsics is False, intrinsics.json."""
    folder.mkdir(parents=True, exist_ok=True)
    for index, name in enumerate(names):
        color, depth = pair_images(index, size)
        assert cv2.imwrite(str(folder / f"image_{name}.png"), color)
        assert cv2.imwrite(str(folder / f"depth_{name}.png"), depth)
    if intrinsics:
        write_intrinsics(folder / "intrinsics.json", size)
    return folder


def write_intrinsics(path: Path, size=(64, 48)) -> Path:
    path.write_text(json.dumps({"K": K_TEST, "dist": DIST_TEST, "image_size": list(size)}))
    return path


def write_bag(path: Path, count: int = 3, size=(64, 48), depth_size=None, period_s: float = 0.1, info=True,
              color_topic="/camera/color/image_raw", depth_topic="/camera/aligned_depth_to_color/image_raw") -> Path:
    """A rosbag2 (sqlite3) folder: `count` colour (rgb8) + depth (16UC1) pairs with equal stamps `period_s` apart,
    and camera_info (K_TEST) on /camera/color/camera_info unless info is False."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    Image, CameraInfo = store.types["sensor_msgs/msg/Image"], store.types["sensor_msgs/msg/CameraInfo"]
    Header, Time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    RegionOfInterest = store.types["sensor_msgs/msg/RegionOfInterest"]
    width, height = size
    with Writer(path, version=9) as writer:
        color_conn = writer.add_connection(color_topic, Image.__msgtype__, typestore=store)
        depth_conn = writer.add_connection(depth_topic, Image.__msgtype__, typestore=store)
        info_conn = writer.add_connection("/camera/color/camera_info", CameraInfo.__msgtype__, typestore=store) if info else None
        for index in range(count):
            t_ns = 1_000_000_000 + int(index * period_s * 1e9)
            header = Header(stamp=Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000), frame_id="camera")
            color_bgr, depth = pair_images(index, size)
            if depth_size is not None:
                depth = cv2.resize(depth, depth_size, interpolation=cv2.INTER_NEAREST)
            rgb = np.ascontiguousarray(color_bgr[..., ::-1])
            color_msg = Image(header=header, height=height, width=width, encoding="rgb8", is_bigendian=0, step=width * 3,
                              data=rgb.reshape(-1))
            dh, dw = depth.shape
            depth_msg = Image(header=header, height=dh, width=dw, encoding="16UC1", is_bigendian=0, step=dw * 2,
                              data=np.frombuffer(depth.astype("<u2").tobytes(), np.uint8))
            writer.write(color_conn, t_ns, store.serialize_cdr(color_msg, Image.__msgtype__))
            writer.write(depth_conn, t_ns + 1000, store.serialize_cdr(depth_msg, Image.__msgtype__))
            if info_conn is not None:
                roi = RegionOfInterest(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
                info_msg = CameraInfo(header=header, height=height, width=width, distortion_model="plumb_bob",
                                      d=np.array(DIST_TEST), k=np.array(K_TEST).reshape(-1), r=np.eye(3).reshape(-1),
                                      p=np.zeros(12), binning_x=0, binning_y=0, roi=roi)
                writer.write(info_conn, t_ns + 2000, store.serialize_cdr(info_msg, CameraInfo.__msgtype__))
    return path
