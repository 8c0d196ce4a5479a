"""The recorder's 100 Hz and 30 Hz messages built cheaply stay the same bytes: /tf with its caches (fixed frames'
parts kept, the URDF's links kept while the arm and the gripper rest) equals /tf built from nothing at every step
(the arm moving, resting, the gripper opening, a fixed frame moved), and /joint_states equals the per-element build."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from armlab.kinematics import load_arm
from armlab.recording import channels as ch
from armlab.recording.sampler import StationSampler
from armlab.station.config import RecordingConfig


class Captured:
    def __init__(self) -> None:
        self.messages: list[bytes] = []

    def log(self, message, log_time: int) -> None:
        self.messages.append(message.encode())


def tf_bytes(sampler: StationSampler, q, width_m: float, time_ns: int) -> bytes:
    sampler._transforms(np.asarray(q, dtype=float), SimpleNamespace(width_m=width_m), time_ns)
    return sampler.channels.tf.messages[-1]


def fresh_sampler(station) -> StationSampler:
    return StationSampler(station, SimpleNamespace(tf=Captured()), RecordingConfig())


def test_cached_transforms_equal_transforms_built_from_nothing():
    model = load_arm("rx200")
    station = SimpleNamespace(has_arm=True, model=model, calibration=SimpleNamespace(T_world_camera=np.eye(4)))
    home = np.asarray(model.home_rad, dtype=float)
    steps = [(home, 0.03), (home, 0.03), (home + 0.2, 0.03), (home + 0.2, 0.03), (home + 0.2, 0.01), (home, 0.01)]
    kept = fresh_sampler(station)
    for index, (q, width_m) in enumerate(steps):
        if index == 4:  # the camera recalibrated: a fixed frame's new pose is recorded, not the cached one
            camera = np.eye(4)
            camera[:3, 3] = (0.1, -0.2, 0.9)
            camera[:3, :3] = [[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]
            station.calibration = SimpleNamespace(T_world_camera=camera)
        time_ns = 1_000_000_000 * (index + 1) + 7
        assert tf_bytes(kept, q, width_m, time_ns) == tf_bytes(fresh_sampler(station), q, width_m, time_ns), index
    last = kept.channels.tf.messages[-1]
    assert all(name in last for name in (b"base", b"camera", b"gripper", b"left_finger_link", b"tool_point"))


def test_frame_transforms_with_parts_equal_without():
    parts: dict = {}
    rotation = np.array([[math.cos(0.3), -math.sin(0.3), 0.0, 0.1], [math.sin(0.3), math.cos(0.3), 0.0, -0.0],
                         [0.0, 0.0, 1.0, 0.5], [0.0, 0.0, 0.0, 1.0]])
    for index, T in enumerate([np.eye(4), rotation, rotation, np.eye(4)]):
        poses = {"base": np.eye(4), "moving": T}
        links = [("base", "link", T)]
        assert ch.frame_transforms(index, poses, links, parts).encode() == ch.frame_transforms(index, poses, links).encode(), index


def test_joint_states_equal_the_per_element_build():
    names = ["waist", "shoulder", "elbow"]
    q, v = np.array([0.1, -0.25, 1.5]), np.array([0.0, -1e-3, 2.0])
    reference = ch.JointStates(timestamp=ch.stamp(123), joints=[
        ch.JointState(name=n, position=float(a), velocity=float(b)) for n, a, b in zip(names, q, v)])
    assert ch.joint_states(123, names, q, v).encode() == reference.encode()
    assert ch.joint_states(123, names, list(q), tuple(v)).encode() == reference.encode()
    no_velocity = ch.JointStates(timestamp=ch.stamp(5), joints=[
        ch.JointState(name=n, position=float(a), velocity=math.nan) for n, a in zip(names, q)])
    assert ch.joint_states(5, names, q).encode() == no_velocity.encode()


TILTED_URDF = """<robot name="t">
  <link name="a"/><link name="b"/><link name="c"/><link name="d"/><link name="e"/>
  <joint name="turn" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.1 0.2 0.3" rpy="0.3 -0.2 1.1"/><axis xyz="0.3 0.4 0.866"/></joint>
  <joint name="spin" type="continuous"><parent link="b"/><child link="c"/><origin xyz="0 0 0.05"/><axis xyz="1 1 0"/></joint>
  <joint name="slide" type="prismatic"><parent link="c"/><child link="d"/><origin xyz="0.01 0 0" rpy="0 1.2 0"/><axis xyz="0 0.6 0.8"/></joint>
  <joint name="bolt" type="fixed"><parent link="d"/><child link="e"/><origin xyz="0 0 0.02" rpy="0.1 0 0"/></joint>
</robot>"""


def test_urdf_transforms_in_one_pass_equal_each_joints_own_motion():
    """UrdfFrames.transforms computes every moving joint at once: the same matrices as each joint's origin times its
    own motion (_axis_motion), for revolute, continuous (tilted axes) and prismatic joints."""
    from armlab.recording.urdf_frames import UrdfFrames, _axis_motion, station_urdf

    rng = np.random.default_rng(4)
    for urdf in (TILTED_URDF, station_urdf(SimpleNamespace(model=load_arm("rx200")))):
        frames = UrdfFrames(urdf)
        for _ in range(50):
            positions = {joint.name: float(rng.uniform(-3.0, 3.0)) for joint in frames.joints}
            expected = [(joint.parent, joint.child, joint.origin @ _axis_motion(joint.kind, joint.axis, positions[joint.name]))
                        for joint in frames.joints]
            got = frames.transforms(positions)
            assert [link[:2] for link in got] == [link[:2] for link in expected]
            for (_, child, T), (_, _, T_expected) in zip(got, expected):
                assert np.allclose(T, T_expected, atol=1e-12, rtol=0.0), child
        assert np.allclose(frames.transforms({})[0][2], frames.joints[0].origin)  # a joint not given: at 0
