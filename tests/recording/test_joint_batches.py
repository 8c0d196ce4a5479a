"""A recording's joint messages (StationSampler with batch_joints, as recorder.py makes it) are read every tick and
written at the slow tick, all together: the same messages as logged at once (each with its own log time and its
reading's header time, in the order read), and a stopped sampler writes the ones still waiting."""

from __future__ import annotations

import json
import threading
import time
from types import SimpleNamespace

import numpy as np

from armlab.devices.arm import JointState
from armlab.kinematics import load_arm
from armlab.recording.sampler import StationSampler
from armlab.station.config import RecordingConfig
from armlab.station.slots import EventLog, NewestSlot
from armlab.station.states import State


class Captured:
    def __init__(self) -> None:
        self.logged: list[tuple[int, bytes]] = []

    def log(self, message, log_time: int) -> None:
        self.logged.append((log_time, message.encode() if hasattr(message, "encode") else json.dumps(message).encode()))

    def close(self) -> None:
        pass


class MovingArmStation:
    """An arm whose every reading is new (its own time, positions and velocities); the commanded joints change too."""

    has_arm = True
    calibration = None

    def __init__(self) -> None:
        self.model = load_arm("rx200")
        self.arm = self
        self.reads = 0
        self.events, self.frames, self.perception = EventLog(), NewestSlot(), NewestSlot()
        self.state = State.IDLE
        self.gripper = SimpleNamespace(read_state=lambda: SimpleNamespace(width_m=0.03, holding=False, command="release"))
        self._lock = threading.Lock()
        self._position = np.asarray(self.model.home_rad, dtype=float).copy()  # one array, changed in place

    def read_joint_state(self) -> JointState:
        with self._lock:
            self.reads += 1
            self._position += 0.001  # a driver reusing its buffer: the sampler must copy what it keeps
            return JointState(self._position, np.full(self.model.dof, 0.01 * self.reads), 1_700_000_000.0 + self.reads / 100)

    def commanded_joints_rad(self) -> np.ndarray:
        return self._position + 0.5

    def current_job(self):
        return None


def channels() -> SimpleNamespace:
    return SimpleNamespace(**{name: Captured() for name in ("joint_states", "joint_commands", "gripper", "tf", "color", "depth",
                                                            "calibration", "detections", "detections_scene", "plan", "events")})


def test_batched_joint_messages_equal_the_ones_logged_at_once(monkeypatch):
    clock = iter(range(10**18, 10**18 + 1000))
    monkeypatch.setattr(time, "time_ns", lambda: next(clock))  # the same log times for both samplers
    at_once = StationSampler(MovingArmStation(), channels(), RecordingConfig())
    batched = StationSampler(MovingArmStation(), channels(), RecordingConfig(), batch_joints=True)
    for sampler in (at_once, batched):
        clock = iter(range(10**18, 10**18 + 1000))
        for _ in range(4):
            sampler._joints()
    assert len(at_once.channels.joint_states.logged) == 4 and len(at_once.channels.joint_commands.logged) == 4
    assert batched.channels.joint_states.logged == [] and batched.channels.joint_commands.logged == []  # not yet
    batched._write_joints()
    for topic in ("joint_states", "joint_commands"):
        assert getattr(batched.channels, topic).logged == getattr(at_once.channels, topic).logged, topic
    assert batched.counts["/joint_states"] == 4 and batched.counts["/joint_commands"] == 4


def test_a_stopped_sampler_writes_the_joint_readings_still_waiting():
    station = MovingArmStation()
    # transforms once a second: the slow tick (the batch's write) comes once, at the first tick
    sampler = StationSampler(station, channels(), RecordingConfig(camera_rate_hz=0, depth_rate_hz=0, joint_rate_hz=200,
                                                                  transforms_rate_hz=1), batch_joints=True)
    sampler.start()
    deadline = time.monotonic() + 20
    while sampler.ticks < 5:
        assert time.monotonic() < deadline, "the sampler did not tick"
        time.sleep(0.005)
    assert sampler.stop()
    logged = sampler.channels.joint_states.logged
    assert len(logged) == station.reads  # every reading (each a new one) recorded, the waiting ones at the stop
    assert [log_time for log_time, _ in logged] == sorted(log_time for log_time, _ in logged)
