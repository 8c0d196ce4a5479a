"""ROS 2 bags (rosbag2: sqlite3 or MCAP storage) of sensor_msgs/msg/JointState, read and written with `rosbags`
(no ROS install).

Reading: a bag folder (metadata.yaml and its .db3 or .mcap files), a bare .mcap or .db3 file, or (bytes, from
an upload) one of those files or a .zip of the folder. The joint states topic is the only JointState topic,
else the only one whose name has no "command" in it, else the one asked for. Names are matched to the arm's
(`waist` or `rx200/waist` both name the RX200's waist; a UR driver's `shoulder_pan_joint` names the UR3's
`shoulder_pan`); every arm joint must be in every message, and a name that is neither an arm joint nor a
gripper joint (GRIPPER_JOINTS) refuses the bag. The gripper command of
each sample comes from the fingers (`left_finger`, or `right_finger` negated: metres from the centre line,
the Interbotix convention): closed by more than a quarter of the arm's finger travel is 'grasp'; without
fingers, from the `gripper` joint (rad): its higher half is open, when it moves by at least 0.2 rad; with
neither, every sample is 'release' (said in the notes). Times are the messages' header stamps (the bag's
receive time when a stamp is zero), from the first sample.

Writing: a program's timed rows (armlab.program_io.timed_rows) as JointState messages on /<arm>/joint_states,
the arm's joints and, for a finger gripper, left_finger/right_finger at the open (release) or closed (grasp)
offset; an MCAP bag unless sqlite3 is asked for. A .mcap path gets the bare MCAP file (ros2 bag play reads it);
any other path a bag folder.
"""

from __future__ import annotations

import io
import shutil
import tempfile
import zipfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from armlab.program_formats.samples import JointSamples
from armlab.program_io import ProgramFileError

JOINT_STATE = "sensor_msgs/msg/JointState"
GRIPPER_JOINTS = ("gripper", "left_finger", "right_finger")
STORAGES = ("mcap", "sqlite3")
MAX_UPLOAD_BYTES = 200_000_000
MAX_SAMPLES = 2_000_000
GRIPPER_ANGLE_SPAN_RAD = 0.2
MCAP_MAGIC = b"\x89MCAP0\r\n"
SQLITE_MAGIC = b"SQLite format 3\x00"


def _typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def read_joint_states(path: str | Path, joint_names: Sequence[str], finger_range_m: tuple[float, float] | None = None,
                      topic: str | None = None) -> JointSamples:
    """The bag's joint states as samples in the arm's joint order; ProgramFileError saying what is wrong."""
    from rosbags.highlevel import AnyReader

    path = Path(path)
    if not path.exists():
        raise ProgramFileError(f"{path}: no such file or folder")
    if path.is_file() and path.stat().st_size == 0:
        raise ProgramFileError(f"{path}: the file is empty, not a ROS 2 bag")
    if path.is_file() and path.suffix.lower() == ".zip":
        return read_joint_states_bytes(path.read_bytes(), joint_names, finger_range_m, topic)
    try:
        reader = AnyReader([path], default_typestore=_typestore())
        reader.open()
    except Exception as error:  # noqa: BLE001 - rosbags raises several types for a damaged bag; all mean "unreadable"
        raise ProgramFileError(f"{path}: not a readable ROS 2 bag ({type(error).__name__}: {error})") from None
    try:
        chosen, notes = _choose_topic(reader.connections, topic, path)
        connections = [c for c in reader.connections if c.topic == chosen]
        rows, stamps = [], []
        try:
            for connection, timestamp_ns, rawdata in reader.messages(connections=connections):
                message = reader.deserialize(rawdata, connection.msgtype)
                stamp = message.header.stamp
                stamp_ns = int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)
                stamps.append(stamp_ns if stamp_ns > 0 else int(timestamp_ns))
                rows.append((list(message.name), np.asarray(message.position, dtype=float)))
                if len(rows) > MAX_SAMPLES:
                    raise ProgramFileError(f"{path}: {chosen} has more than {MAX_SAMPLES} messages")
        except ProgramFileError:
            raise
        except Exception as error:  # noqa: BLE001 - a truncated or damaged bag: name it
            raise ProgramFileError(f"{path}: the bag is damaged or truncated after {len(rows)} messages of {chosen} "
                                   f"({type(error).__name__}: {error}); nothing was imported") from None
    finally:
        try:
            reader.close()
        except Exception:  # noqa: BLE001 - closing after a failed read
            pass
    if not rows:
        raise ProgramFileError(f"{path}: the topic {chosen} has no messages")
    return _samples(rows, np.asarray(stamps, dtype=np.int64), joint_names, finger_range_m, chosen, notes)


def read_joint_states_bytes(data: bytes, joint_names: Sequence[str], finger_range_m: tuple[float, float] | None = None,
                            topic: str | None = None) -> JointSamples:
    """read_joint_states of an uploaded bag: a bare .mcap or .db3 file, or a .zip of a bag folder."""
    if not data:
        raise ProgramFileError("the upload is empty, not a ROS 2 bag")
    if len(data) > MAX_UPLOAD_BYTES:
        raise ProgramFileError(f"the upload has {len(data)} bytes; at most {MAX_UPLOAD_BYTES}")
    with tempfile.TemporaryDirectory(prefix="armlab-bag-") as folder:
        root = Path(folder)
        if data.startswith(MCAP_MAGIC):
            path = root / "upload.mcap"
            path.write_bytes(data)
        elif data.startswith(SQLITE_MAGIC):
            path = root / "upload.db3"
            path.write_bytes(data)
        elif data.startswith(b"PK\x03\x04"):
            path = _unzipped(data, root / "bag")
        else:
            raise ProgramFileError("not a ROS 2 bag: expected an MCAP file, a rosbag2 .db3 (SQLite) file or a .zip of a bag folder")
        return read_joint_states(path, joint_names, finger_range_m, topic)


def _unzipped(data: bytes, into: Path) -> Path:
    """The bag folder inside a zip (its metadata.yaml's folder, or the only bag file); ProgramFileError otherwise."""
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
        members = [m for m in archive.infolist() if not m.is_dir()]
        if sum(m.file_size for m in members) > MAX_UPLOAD_BYTES:
            raise ProgramFileError(f"the zip unpacks to more than {MAX_UPLOAD_BYTES} bytes")
        into.mkdir(parents=True)
        for member in members:
            target = (into / member.filename).resolve()
            if into.resolve() not in target.parents:
                raise ProgramFileError(f"the zip has a path outside its folder: {member.filename!r}")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(archive.read(member))
    except (zipfile.BadZipFile, EOFError, OSError) as error:
        raise ProgramFileError(f"not a readable zip ({error})") from None
    metadata = sorted(into.rglob("metadata.yaml"))
    if len(metadata) == 1:
        return metadata[0].parent
    files = [p for p in into.rglob("*") if p.suffix in (".mcap", ".db3")]
    if len(files) == 1:
        return files[0]
    raise ProgramFileError(f"the zip holds {len(metadata)} metadata.yaml and {len(files)} bag files; expected one bag")


def _choose_topic(connections, topic: str | None, path: Path) -> tuple[str, list[str]]:
    types = {c.topic: c.msgtype for c in connections}
    joint_topics = sorted(t for t, kind in types.items() if kind == JOINT_STATE)
    listing = ", ".join(f"{t} ({types[t]})" for t in sorted(types)) or "none"
    if topic is not None:
        if topic not in joint_topics:
            raise ProgramFileError(f"{path}: no {JOINT_STATE} topic {topic!r} (topics: {listing})")
        return topic, []
    if not joint_topics:
        raise ProgramFileError(f"{path}: the bag has no {JOINT_STATE} topic, no joint states to import (topics: {listing})")
    if len(joint_topics) == 1:
        return joint_topics[0], []
    measured = [t for t in joint_topics if "command" not in t.lower()]
    if len(measured) == 1:
        return measured[0], [f"read {measured[0]} (the bag's other joint states: {', '.join(t for t in joint_topics if t != measured[0])})"]
    raise ProgramFileError(f"{path}: several joint state topics ({', '.join(joint_topics)}); name one (topic)")


def _samples(rows, stamps_ns: np.ndarray, joint_names: Sequence[str], finger_range_m, topic: str, notes: list[str]) -> JointSamples:
    """Samples in the arm's joint order from (names, positions) rows; ProgramFileError for other names or counts."""
    order = np.argsort(stamps_ns, kind="stable")
    arm = list(joint_names)
    positions = np.empty((len(rows), len(arm)))
    fingers = np.full(len(rows), np.nan)
    angles = np.full(len(rows), np.nan)
    for out, index in enumerate(order):
        names, values = rows[index]
        where = f"{topic} message {index + 1}"
        if len(values) != len(names):
            raise ProgramFileError(f"{where}: {len(names)} joint names but {len(values)} positions")
        short = [_short(str(name), arm) for name in names]
        unknown = [name for name in short if name not in arm and name not in GRIPPER_JOINTS]
        missing = [name for name in arm if name not in short]
        if unknown or missing:
            raise ProgramFileError(
                f"{where}: joints {', '.join(map(str, names)) or '(none)'} are not this arm's "
                f"({', '.join(arm)}, and {'/'.join(GRIPPER_JOINTS)})"
                + (f": unknown {', '.join(unknown)}" if unknown else "") + (f"; missing {', '.join(missing)}" if missing else "")
            )
        if len(set(short)) != len(short):
            raise ProgramFileError(f"{where}: a joint name appears twice ({', '.join(map(str, names))})")
        lookup = dict(zip(short, values))
        positions[out] = [lookup[name] for name in arm]
        if "left_finger" in lookup:
            fingers[out] = lookup["left_finger"]
        elif "right_finger" in lookup:
            fingers[out] = -lookup["right_finger"]
        if "gripper" in lookup:
            angles[out] = lookup["gripper"]
    times_s = (stamps_ns[order] - stamps_ns[order][0]) / 1e9
    gripper, gripper_note = _gripper(fingers, angles, finger_range_m)
    return JointSamples(times_s, positions, gripper, tuple([*notes, f"read {len(rows)} joint states from {topic}", gripper_note]))


def _short(name: str, arm: list[str]) -> str:
    """A message's joint name as the arm names it: without a namespace (`rx200/waist`) and, when that makes it
    the arm's, without a `_joint` suffix (a UR driver's `shoulder_pan_joint`)."""
    name = name.rsplit("/", 1)[-1]
    return name[: -len("_joint")] if name not in arm and name.endswith("_joint") and name[: -len("_joint")] in arm else name


def _gripper(fingers: np.ndarray, angles: np.ndarray, finger_range_m) -> tuple[tuple[str, ...], str]:
    if np.all(np.isfinite(fingers)) and finger_range_m is not None:
        closed_m, open_m = finger_range_m
        threshold = open_m - 0.25 * (open_m - closed_m)
        return tuple("grasp" if v < threshold else "release" for v in fingers), f"gripper from the fingers: closed below {threshold * 1000:.1f} mm"
    if np.all(np.isfinite(angles)):
        low, high = float(angles.min()), float(angles.max())
        if high - low >= GRIPPER_ANGLE_SPAN_RAD:
            middle = (low + high) / 2
            return tuple("grasp" if v < middle else "release" for v in angles), f"gripper from the gripper joint: closed below {middle:.3f} rad"
        return ("release",) * len(angles), f"gripper joint held near {low:.3f} rad throughout: taken as released"
    return ("release",) * len(fingers), "no gripper joints in the bag: every waypoint releases"


def write_joint_states(path: str | Path, rows: Sequence[tuple[float, Sequence[float], str]], joint_names: Sequence[str],
                       finger_range_m: tuple[float, float] | None = None, topic: str = "/rx200/joint_states",
                       storage: str = "mcap", start_ns: int = 1_000_000_000) -> Path:
    """Write (t_s, joints_rad, gripper) rows as JointState messages (stamped start_ns + t_s); returns the path
    written (a bag folder, or a bare .mcap file when path ends in .mcap)."""
    path = Path(path)
    if storage not in STORAGES:
        raise ProgramFileError(f"storage must be one of {', '.join(STORAGES)}, not {storage!r}")
    bare = path.suffix == ".mcap"
    if bare and storage != "mcap":
        raise ProgramFileError(f"{path}: a .mcap file holds MCAP storage, not {storage}")
    if path.exists():
        raise ProgramFileError(f"{path} exists already: give a new path")
    with tempfile.TemporaryDirectory(prefix="armlab-bag-", dir=path.parent if path.parent.exists() else None) as folder:
        bag = Path(folder) / (path.stem if bare else path.name)
        _write(bag, rows, joint_names, finger_range_m, topic, storage, start_ns)
        if bare:
            shutil.move(str(next(bag.glob("*.mcap"))), path)
        else:
            shutil.move(str(bag), path)
    return path


def joint_states_bytes(rows, joint_names: Sequence[str], finger_range_m=None, topic: str = "/rx200/joint_states",
                       start_ns: int = 1_000_000_000) -> bytes:
    """The rows as one MCAP file's bytes (a download)."""
    with tempfile.TemporaryDirectory(prefix="armlab-bag-") as folder:
        bag = Path(folder) / "program"
        _write(bag, rows, joint_names, finger_range_m, topic, "mcap", start_ns)
        return next(bag.glob("*.mcap")).read_bytes()


def _write(bag: Path, rows, joint_names, finger_range_m, topic: str, storage: str, start_ns: int) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = _typestore()
    JointState = store.types[JOINT_STATE]
    Header, Time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    names = [*joint_names, *(("left_finger", "right_finger") if finger_range_m is not None else ("gripper",))]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(bag, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection(topic, JOINT_STATE, typestore=store)
        for t_s, joints, gripper in rows:
            if finger_range_m is not None:
                offset = finger_range_m[0] if gripper == "grasp" else finger_range_m[1]
                extra = [offset, -offset]
            else:
                extra = [0.0 if gripper == "grasp" else 1.0]
            stamp_ns = int(start_ns + round(float(t_s) * 1e9))
            message = JointState(
                header=Header(stamp=Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000), frame_id=""),
                name=names, position=np.array([*joints, *extra], dtype=float),
                velocity=np.zeros(0), effort=np.zeros(0),
            )
            writer.write(connection, stamp_ns, store.serialize_cdr(message, JOINT_STATE))


def write_trace(path_or_none: str | Path | None, samples: Sequence[Sequence[float]], joint_names: Sequence[str], arm: str = "rx200",
                start_ns: int = 1_000_000_000) -> bytes | Path:
    """A repeat's cycle trace ([t_s, commanded × dof, measured × dof] rows) as a bag: measured on
    /<arm>/joint_states, commanded on /<arm>/commanded/joint_states. Bytes of one MCAP file when path is None."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = _typestore()
    JointState = store.types[JOINT_STATE]
    Header, Time = store.types["std_msgs/msg/Header"], store.types["builtin_interfaces/msg/Time"]
    dof = len(joint_names)
    with tempfile.TemporaryDirectory(prefix="armlab-bag-") as folder:
        bag = Path(folder) / "trace"
        with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
            measured = writer.add_connection(f"/{arm}/joint_states", JOINT_STATE, typestore=store)
            commanded = writer.add_connection(f"/{arm}/commanded/joint_states", JOINT_STATE, typestore=store)
            for row in samples:
                stamp_ns = int(start_ns + round(float(row[0]) * 1e9))
                header = Header(stamp=Time(sec=stamp_ns // 1_000_000_000, nanosec=stamp_ns % 1_000_000_000), frame_id="")
                for connection, values in ((commanded, row[1 : 1 + dof]), (measured, row[1 + dof : 1 + 2 * dof])):
                    message = JointState(header=header, name=list(joint_names), position=np.array(values, dtype=float),
                                         velocity=np.zeros(0), effort=np.zeros(0))
                    writer.write(connection, stamp_ns, store.serialize_cdr(message, JOINT_STATE))
        written = next(bag.glob("*.mcap"))
        if path_or_none is None:
            return written.read_bytes()
        shutil.move(str(written), path_or_none)
        return Path(path_or_none)
