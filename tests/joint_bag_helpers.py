"""ROS 2 bags of sensor_msgs/JointState written with `rosbags` itself (no armlab code), for the program import
tests: an RX200 recording of a pick (rest at A, move to B, close the fingers, move to C, rest) with literal poses."""

from __future__ import annotations

from pathlib import Path

import numpy as np

RX200_NAMES = ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate", "gripper", "left_finger", "right_finger"]
POSE_A = (0.0, -0.3, 0.3, 0.9, 0.0)
POSE_B = (0.45, 0.05, 0.35, 1.0, 0.0)
POSE_C = (0.9, 0.2, 0.1, 1.1, 0.3)
OPEN_M, HOLDING_M = 0.037, 0.025  # left_finger: fully open; closed on a 38 mm block
RATE_HZ = 100.0


def pick_rows(pose_a=POSE_A, pose_b=POSE_B, pose_c=POSE_C) -> list[tuple[float, list[float]]]:
    """(t_s, [5 joints, gripper rad, left_finger m, right_finger m]) at 100 Hz: 0.3 s at A, a 1 s move to B (cosine
    speed profile), 0.5 s still, the fingers close over 0.5 s, 0.3 s still, a 1 s move to C, 0.4 s still."""
    rows, t = [], 0.0
    step = 1.0 / RATE_HZ

    def add(q, finger):
        nonlocal t
        rows.append((round(t, 6), [*q, 1.2 if finger > 0.031 else 0.2, finger, -finger]))
        t += step

    def hold(q, finger, seconds):
        for _ in range(int(round(seconds * RATE_HZ))):
            add(q, finger)

    def move(q0, q1, finger, seconds):
        n = int(round(seconds * RATE_HZ))
        for i in range(1, n + 1):
            s = (1 - np.cos(np.pi * i / n)) / 2
            add([a + s * (b - a) for a, b in zip(q0, q1)], finger)

    hold(pose_a, OPEN_M, 0.3)
    move(pose_a, pose_b, OPEN_M, 1.0)
    hold(pose_b, OPEN_M, 0.5)
    for i in range(1, 51):
        add(pose_b, OPEN_M - (OPEN_M - HOLDING_M) * i / 50)
    hold(pose_b, HOLDING_M, 0.3)
    move(pose_b, pose_c, HOLDING_M, 1.0)
    hold(pose_c, HOLDING_M, 0.4)
    return rows


def write_joint_bag(path: Path, rows, names=RX200_NAMES, storage: str = "mcap", topic: str = "/rx200/joint_states",
                    other_topic: bool = False, start_ns: int = 1_700_000_000_000_000_000) -> Path:
    """A rosbag2 folder with one JointState per row on `topic` (names as given, positions as given, even when
    their counts differ); other_topic: a std_msgs/String topic besides it."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState, String = store.types["sensor_msgs/msg/JointState"], store.types["std_msgs/msg/String"]
    Header, Time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        joints = writer.add_connection(topic, JointState.__msgtype__, typestore=store) if rows is not None else None
        note = writer.add_connection("/notes", String.__msgtype__, typestore=store) if other_topic or rows is None else None
        for t_s, positions in rows or []:
            ns = start_ns + int(round(t_s * 1e9))
            message = JointState(header=Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=""), name=list(names),
                                 position=np.asarray(positions, dtype=float), velocity=np.zeros(0), effort=np.zeros(0))
            writer.write(joints, ns, store.serialize_cdr(message, JointState.__msgtype__))
        if note is not None:
            writer.write(note, start_ns, store.serialize_cdr(String(data="no joints here"), String.__msgtype__))
    return path
