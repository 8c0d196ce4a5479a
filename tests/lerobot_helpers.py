"""Recordings with known contents for the LeRobot export's tests, written by the recorder's own file and channels
(McapFile, StationChannels.on_file, the channels' message builders): the RX200's five joints at 100 Hz in a sine,
the commanded joints at 100 Hz for the first `commanded_s` seconds (then none: a teach session by hand), the gripper
at 30 Hz (grasp after 2 s), and colour frames at `camera_hz`, frame i a flat grey of level(i) (JPEG)."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np

from armlab.recording import StationChannels
from armlab.recording import channels as ch
from armlab.recording.mcap_file import McapFile

NAMES = ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"]
START_NS = 1_800_000_000 * 10**9
RECORDING_ID = "20270115T080000Z-abc123"


def level(index: int) -> int:
    """Colour frame i's grey level: neighbours 8 apart, so a frame off by one shows."""
    return 16 + (index * 8) % 224


def joints_at(t_s: float) -> list[float]:
    return [0.1 * j + 0.5 * math.sin(2 * math.pi * 0.5 * t_s + j) for j in range(len(NAMES))]


def command_at(t_s: float) -> list[float]:
    return [q + 0.01 for q in joints_at(t_s)]


def write_recording(path: Path, seconds: float = 3.0, *, camera_hz: float = 15.0, camera_size: tuple[int, int] = (64, 48),
                    commanded_s: float = 1.0, camera: bool = True, label: str = "stack three", chunk_kb: int = 16,
                    camera_offset_s: float = 0.05) -> Path:
    """A complete recording at `path` (a library name: <id>.mcap). Times: START_NS + t."""
    file = McapFile(path, chunk_kb * 1024)
    channels = StationChannels.on_file(file)
    file.write_metadata("armlab", {"id": path.stem, "label": label, "source": "test", "workcell": "rx200_armlab",
                                   "joint_names": ",".join(NAMES)})
    events = []
    for i in range(int(seconds * 100) + 1):
        t = i / 100
        events.append((t, "joints", i))
        if t < commanded_s:
            events.append((t, "command", i))
    for i in range(int(seconds * 30) + 1):
        events.append((i / 30, "gripper", i))
    if camera:
        for i in range(int((seconds - camera_offset_s) * camera_hz) + 1):
            events.append((camera_offset_s + i / camera_hz, "color", i))
    width, height = camera_size
    for t, kind, i in sorted(events):
        ns = START_NS + round(t * 1e9)
        if kind == "joints":
            channels.joint_states.log(ch.joint_states(ns, NAMES, joints_at(t), [0.0] * 5), log_time=ns)
        elif kind == "command":
            channels.joint_commands.log(ch.joint_states(ns, NAMES, command_at(t)), log_time=ns)
        elif kind == "gripper":
            channels.gripper.log({"time_s": ns / 1e9, "width_m": 0.03 - 0.005 * t, "holding": t >= 2.0,
                                  "command": "grasp" if t >= 2.0 else "release"}, log_time=ns)
        else:
            ok, jpeg = cv2.imencode(".jpg", np.full((height, width, 3), level(i), np.uint8), [int(cv2.IMWRITE_JPEG_QUALITY), 95])
            channels.color.log(ch.compressed_image(ns, jpeg.tobytes()), log_time=ns)
    file.close()
    return path


def newest_at_or_before(times_ns: list[int], t_ns: int) -> int:
    """The index of the newest time at or before t_ns, by a plain scan (the test's own, not the exporter's)."""
    found = -1
    for index, time_ns in enumerate(times_ns):
        if time_ns <= t_ns:
            found = index
    return found


class SineArmStation:
    """What the recorder samples of a station, with an arm: the RX200's model (kinematics only, no simulation), joints
    in a sine read at time.time(), the commanded reference a little ahead of them, a gripper, and 64x48 colour frames
    published at about 30 fps (frame i a flat grey of level(i)). Start it with `with`."""

    has_arm = True
    backend = "test"
    calibration = None

    class config:  # noqa: N801 - stands in for StationConfig
        workcell = "rx200_armlab"

    def __init__(self) -> None:
        import threading
        import time

        from armlab.devices.camera import Intrinsics
        from armlab.kinematics import load_arm
        from armlab.station.slots import EventLog, NewestSlot
        from armlab.station.states import State

        self.model = load_arm("rx200")
        self.events, self.frames, self.perception = EventLog(), NewestSlot(), NewestSlot()
        self.state = State.IDLE
        self.arm = self.gripper = self.intrinsics = self
        self._intrinsics = Intrinsics(64, 48, 50.0, 50.0, 32.0, 24.0)
        self._start_s = time.time()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._camera, name="test-camera", daemon=True)

    def current(self):
        return self._intrinsics

    def current_job(self):
        return None

    def _q(self, t_s: float) -> np.ndarray:
        return np.asarray(self.model.home_rad) + 0.3 * math.sin(2.0 * (t_s - self._start_s))

    def read_joint_state(self):
        import time

        from armlab.devices.arm import JointState

        now = time.time()
        return JointState(self._q(now), np.zeros(self.model.dof), now)

    def commanded_joints_rad(self) -> np.ndarray:
        import time

        return self._q(time.time() + 0.05)

    def read_state(self):
        import time

        from armlab.devices.gripper import GripperState

        now = time.time()
        return GripperState(width_m=0.02 + 0.01 * math.sin(now - self._start_s), command="grasp" if int(now * 2) % 2 else "release",
                            holding=False, timestamp_s=now)

    def _camera(self) -> None:
        import time

        from armlab.devices.camera import Frame

        sequence = 0
        while not self._stop.wait(1 / 30):
            color = np.full((48, 64, 3), level(sequence), np.uint8)
            self.frames.publish(Frame(color, np.full((48, 64), 500, np.uint16), time.time(), sequence, self._intrinsics))
            sequence += 1

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5)
