"""A real arm's recording plays back as a repeat (issue 23 item 4): a ROS 2 bag of RX200 joint states written by
`rosbags` imports as a program (thinned, the gripper step kept) that repeats on the simulated station: every
commanded and measured joint inside the limits, the arm through each recorded pose, home at the end;
the cycle's trace exports as a bag that reads back sample for sample."""

from __future__ import annotations

import numpy as np

from armlab import skills
from armlab.skills.program_files import import_program_file, trace_bag
from joint_bag_helpers import POSE_A, POSE_B, POSE_C, pick_rows, write_joint_bag

REACHED_RAD = 0.02


def test_an_imported_bag_repeats_within_the_limits(fast, tmp_path):
    station, cell = fast
    bag = write_joint_bag(tmp_path / "pick", pick_rows())
    imported = import_program_file(station, "rosbag2", path=bag, name="recorded pick")
    program = imported.program
    assert [(w.joints_rad, w.gripper) for w in program.waypoints] == [
        (POSE_A, "release"), (POSE_B, "release"), (POSE_B, "grasp"), (POSE_C, "grasp")]
    job = skills.repeat(station, program.id, cycles=1, speed_percent=100)
    assert job.wait(300) and job.state == "succeeded", job.message
    snapshot = job.control.trace.snapshot()
    samples = np.asarray(snapshot["samples"])
    dof = len(snapshot["joint_names"])
    commanded, measured = samples[:, 1 : 1 + dof], samples[:, 1 + dof :]
    lower, upper = np.asarray(station.model.lower_rad), np.asarray(station.model.upper_rad)
    for joints in (commanded, measured):
        assert np.all(joints >= lower - 1e-6) and np.all(joints <= upper + 1e-6)
    for pose in (POSE_A, POSE_B, POSE_C):  # the arm went through every recorded pose
        assert np.min(np.max(np.abs(measured - np.asarray(pose)), axis=1)) < REACHED_RAD, pose
    assert np.allclose(station.joints_rad(), 0.0, atol=0.02)  # home at the end

    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    path = tmp_path / "trace.mcap"
    path.write_bytes(trace_bag(station, snapshot["samples"], snapshot["joint_names"]))
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        topics = {c.topic: c for c in reader.connections}
        assert sorted(topics) == ["/rx200/commanded/joint_states", "/rx200/joint_states"]
        read = [reader.deserialize(raw, c.msgtype).position for c, _, raw in reader.messages(connections=[topics["/rx200/joint_states"]])]
    assert np.allclose(np.asarray(read), measured)
