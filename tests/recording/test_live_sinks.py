"""The live Foxglove server without a simulation: an idle server costs the station no encoding (a channel no client
subscribes to is not sampled), a subscribed channel is; the URDF's link transforms compose to the arm model's own
forward kinematics; the plan's scene entity and its deletion."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_recording_library import CameraOnlyStation

from armlab.kinematics import load_arm
from armlab.recording import channels as ch
from armlab.recording.live import LiveServer
from armlab.recording.urdf_frames import UrdfFrames, joint_positions
from armlab.station.arm_urdf import MeshSet, arm_urdf
from armlab.station.config import FoxgloveConfig

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "server"))
import live  # noqa: E402
from foxglove_ws import FoxgloveClient, decoded  # noqa: E402


def test_an_idle_server_encodes_nothing_and_a_subscribed_channel_is_sampled():
    server = LiveServer("127.0.0.1", live.free_port(), FoxgloveConfig(camera_rate_hz=50.0)).start()
    try:
        with CameraOnlyStation() as station:
            server.attach(station)
            sampler = server.sampler
            base = os.getpriority(os.PRIO_PROCESS, 0)  # the live sampler's threads below the station's for the CPU (Linux nice)
            lowest = min(base + 5, 19)  # Linux nice tops out at 19 (a suite run under `nice -n 19` starts there)
            live.wait_for(lambda: all(os.getpriority(os.PRIO_PROCESS, thread.native_id) >= lowest for thread in sampler._threads), 10)
            live.wait_for(lambda: sampler.ticks >= 30 and station.frames.get()[1] >= 10, 20)
            assert sum(sampler.counts.values()) == 0, sampler.counts  # nobody subscribed: nothing built or encoded
            with FoxgloveClient(f"ws://127.0.0.1:{server.port}") as client:
                client.subscribe(["/camera/color/compressed"])
                image, _ = client.next_message("/camera/color/compressed")
                assert image.format == "jpeg" and image.data[:2] == b"\xff\xd8"
                assert sampler.counts["/camera/color/compressed"] >= 1
                assert {topic for topic, count in sampler.counts.items() if count} == {"/camera/color/compressed"}
            live.wait_for(lambda: not server.channels.color.has_sinks(), 10)  # the client left: encoding stops again
            before = sampler.counts["/camera/color/compressed"]
            start = sampler.ticks
            live.wait_for(lambda: sampler.ticks >= start + 30, 20)
            assert sampler.counts["/camera/color/compressed"] <= before + 1  # at most the frame being encoded as it left
    finally:
        server.stop()


def test_urdf_links_compose_to_the_arm_models_forward_kinematics():
    model = load_arm("rx200")
    frames = UrdfFrames(arm_urdf(model.config, np.asarray(model.T_world_base), MeshSet.load(model.name)))
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.uniform(model.lower_rad, model.upper_rad)
        poses = {"world": np.eye(4)}
        for parent, child, T in frames.transforms(joint_positions(model.joint_names, q, 0.02)):
            poses[child] = poses[parent] @ T
        assert np.allclose(poses["tool_point"], model.joint_frames(q)[-1], atol=1e-9)
        for name, frame in zip(model.joint_names, model.joint_frames(q)[:-1]):
            assert np.allclose(poses[f"{name}_link"][:3, 3], frame[:3, 3], atol=1e-9), name
        finger = poses["left_finger_link"][:3, 3] - poses["right_finger_link"][:3, 3]
        assert np.linalg.norm(finger) == pytest.approx(0.04, abs=1e-9)  # each finger 0.02 m off the centre line


def test_the_plan_is_a_scene_entity_and_no_plan_deletes_it():
    now = time.time_ns()
    update = decoded(ch.plan_scene(now, {"next_block": {"position_m": [0.1, 0.2, 0.02], "color": "red", "size": "large"},
                                 "next_target_m": [-0.15, 0.25, 0.04]}))
    (entity,) = update.entities
    assert entity.id == "plan" and entity.frame_id == "world" and entity.texts[0].text == "next: red large"
    points = [(p.x, p.y, p.z) for p in entity.lines[0].points]
    assert points[0] == pytest.approx((0.1, 0.2, 0.02)) and points[-1] == pytest.approx((-0.15, 0.25, 0.04))
    assert min(z for _, _, z in points[1:-1]) > 0.04  # over the blocks, not through them
    cleared = decoded(ch.plan_scene(now, None))
    assert not cleared.entities and cleared.deletions[0].id == "plan"
