"""Program files of other tools (armlab.program_formats, issue 23 item 4): ROS 2 bags of joint states written by
`rosbags` itself and the course's joint text become waypoints equal to what was written (thinned with the gripper
steps and holds kept, or as a trajectory); positions beyond the limits refused or clamped only by an explicit
amount; bags without joint states, with other joint names or counts, empty or truncated, refused."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.program_formats import (
    ImportOptions,
    parse_jointdata,
    read_joint_states,
    read_joint_states_bytes,
    to_program,
    write_joint_states,
)
from armlab.program_io import ProgramFileError
from joint_bag_helpers import HOLDING_M, OPEN_M, POSE_A, POSE_B, POSE_C, RX200_NAMES, pick_rows, write_joint_bag

ARM = load_arm("rx200")
NAMES = list(ARM.joint_names)
FINGERS_M = (0.015, 0.037)


def _convert(samples, **options):
    return to_program(samples, NAMES, ARM.lower_rad, ARM.upper_rad, ImportOptions(**options))


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_recorded_pick_thins_to_its_poses_with_the_gripper_step_kept(tmp_path, storage):
    bag = write_joint_bag(tmp_path / "pick", pick_rows(), storage=storage)
    converted = _convert(read_joint_states(bag, NAMES, FINGERS_M))
    got = converted.waypoints
    assert [w.joints_rad for w in got] == [POSE_A, POSE_B, POSE_B, POSE_C]  # exactly the written poses
    assert [w.gripper for w in got] == ["release", "release", "grasp", "grasp"]  # the gripper step at B kept
    assert got[0].dwell_s == pytest.approx(0.3, abs=0.05) and got[0].moving_time_s is None
    assert got[1].moving_time_s == pytest.approx(1.0, abs=0.1)  # the 1 s move (its slow last mrad counts as the hold)
    assert got[1].dwell_s + got[2].dwell_s == pytest.approx(1.3, abs=0.1)  # 0.5 s still + 0.5 s closing + 0.3 s still
    assert got[2].moving_time_s is None  # a step, not a move
    assert got[3].moving_time_s == pytest.approx(1.0, abs=0.1) and got[3].dwell_s == pytest.approx(0.4, abs=0.05)
    assert converted.samples == 400 and converted.clamped_samples == 0


def test_trajectory_mode_keeps_the_path_every_min_change(tmp_path):
    bag = write_joint_bag(tmp_path / "pick", pick_rows())
    got = _convert(read_joint_states(bag, NAMES, FINGERS_M), mode="trajectory", min_change_rad=0.02).waypoints
    assert got[0].joints_rad == POSE_A and got[-1].joints_rad == POSE_C
    assert ("release", "grasp") in {(a.gripper, b.gripper) for a, b in zip(got, got[1:]) if a.joints_rad == b.joints_rad}
    steps = [np.max(np.abs(np.subtract(b.joints_rad, a.joints_rad))) for a, b in zip(got, got[1:]) if a.gripper == b.gripper]
    assert len(got) > 20 and max(steps) < 0.02 + 0.03  # every kept sample ~min_change from the last (one 100 Hz sample more at most)
    total_s = sum(w.moving_time_s or 0.0 for w in got) + sum(w.dwell_s for w in got)
    assert total_s == pytest.approx(3.99, abs=0.02)  # the recording's 3.99 s (a gripper step takes no time of its own)


def test_names_match_with_a_namespace_and_in_any_order(tmp_path):
    order = [7, 6, 5, 4, 3, 2, 1, 0]
    rows = [(t, [q[i] for i in order]) for t, q in pick_rows()]
    names = [f"rx200/{RX200_NAMES[i]}" for i in order]
    got = _convert(read_joint_states(write_joint_bag(tmp_path / "b", rows, names=names), NAMES, FINGERS_M)).waypoints
    assert [w.joints_rad for w in got] == [POSE_A, POSE_B, POSE_B, POSE_C]


def test_a_ur_drivers_joint_names_match_the_ur3s(tmp_path):
    ur3 = load_arm("ur3")
    names = [f"{name}_joint" for name in ur3.joint_names]
    pose = [0.1, -1.2, 1.0, -1.4, -1.57, 0.2]
    samples = read_joint_states(write_joint_bag(tmp_path / "ur", [(0.0, pose), (0.5, pose)], names=names), list(ur3.joint_names))
    assert samples.positions_rad.tolist() == [pose, pose] and samples.gripper == ("release", "release")
    assert any("no gripper joints" in note for note in samples.notes)


def test_the_gripper_joint_alone_gives_the_steps(tmp_path):
    rows = [(t, q[:6]) for t, q in pick_rows()]
    samples = read_joint_states(write_joint_bag(tmp_path / "b", rows, names=RX200_NAMES[:6]), NAMES, FINGERS_M)
    assert [w.gripper for w in _convert(samples).waypoints] == ["release", "release", "grasp", "grasp"]


def test_a_program_written_as_a_bag_reads_back_row_for_row(tmp_path):
    rows = [(0.0, POSE_A, "release"), (0.5, POSE_A, "release"), (2.0, POSE_B, "release"), (2.0, POSE_B, "grasp"), (3.5, POSE_C, "grasp")]
    for path in (tmp_path / "program.mcap", tmp_path / "program_folder"):
        write_joint_states(path, rows, NAMES, FINGERS_M)
        got = _convert(read_joint_states(path, NAMES, FINGERS_M)).waypoints
        assert [(w.joints_rad, w.gripper) for w in got] == [(POSE_A, "release"), (POSE_B, "release"), (POSE_B, "grasp"), (POSE_C, "grasp")]
        assert [w.dwell_s for w in got] == pytest.approx([0.5, 0.0, 0.0, 0.0])
        assert [w.moving_time_s for w in got] == [None, pytest.approx(1.5), None, pytest.approx(1.5)]
    with pytest.raises(ProgramFileError, match="exists already"):
        write_joint_states(tmp_path / "program.mcap", rows, NAMES, FINGERS_M)


def test_beyond_the_limits_is_refused_unless_clamped_by_an_explicit_amount(tmp_path):
    over = ARM.upper_rad[1] + 0.03  # shoulder 30 mrad beyond its upper limit at B
    rows = [(t, [q[0], over if q[:5] == list(POSE_B) else q[1], *q[2:]]) for t, q in pick_rows()]
    samples = read_joint_states(write_joint_bag(tmp_path / "b", rows), NAMES, FINGERS_M)
    with pytest.raises(ProgramFileError, match=r"joint 'shoulder' = .* outside its limits .* by 0\.0300 rad.*explicit clamp"):
        _convert(samples)
    with pytest.raises(ProgramFileError, match="more than the 0.01 rad clamp allows"):
        _convert(samples, clamp_rad=0.01)
    converted = _convert(samples, clamp_rad=0.05)
    assert converted.clamped_rad == {"shoulder": pytest.approx(0.03)} and converted.clamped_samples > 100
    assert any("clamped" in note and "shoulder by up to 0.0300 rad" in note for note in converted.notes)
    assert max(w.joints_rad[1] for w in converted.waypoints) == pytest.approx(ARM.upper_rad[1])


@pytest.mark.parametrize(
    ("rows", "names", "message"),
    [
        (None, RX200_NAMES, "no sensor_msgs/msg/JointState topic"),
        ([(0.0, [0.0] * 6)], ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"],
         "not this arm's .* unknown shoulder_pan_joint"),
        ([(0.0, [0.0] * 4)], RX200_NAMES[:4], "missing wrist_rotate"),
        ([(0.0, [0.0] * 9)], [*RX200_NAMES, "camera_pan"], "not this arm's .*: unknown camera_pan$"),  # the arm's joints and another's
        ([(0.0, [0.0] * 5)], RX200_NAMES[:6], "6 joint names but 5 positions"),
        ([], RX200_NAMES, "has no messages"),
    ],
)
def test_bags_without_this_arms_joint_states_are_refused(tmp_path, rows, names, message):
    bag = write_joint_bag(tmp_path / "b", rows, names=names)
    with pytest.raises(ProgramFileError, match=message):
        read_joint_states(bag, NAMES, FINGERS_M)


def test_empty_truncated_and_foreign_files_are_refused(tmp_path):
    bag = write_joint_bag(tmp_path / "b", pick_rows())
    data = next(bag.glob("*.mcap")).read_bytes()
    (tmp_path / "empty.mcap").write_bytes(b"")
    (tmp_path / "cut.mcap").write_bytes(data[: len(data) // 2])
    (tmp_path / "text.mcap").write_text("t_s,q1\n0,0\n")
    for name, message in (("empty.mcap", "empty"), ("cut.mcap", "not a readable ROS 2 bag|damaged or truncated"),
                          ("text.mcap", "not a readable ROS 2 bag"), ("missing", "no such file")):
        with pytest.raises(ProgramFileError, match=message):
            read_joint_states(tmp_path / name, NAMES, FINGERS_M)
    with pytest.raises(ProgramFileError, match="damaged or truncated|not a readable"):
        read_joint_states_bytes(data[: len(data) // 2], NAMES, FINGERS_M)
    for upload in (b"", b"t_s,q1,q2\n0,0,0\n"):
        with pytest.raises(ProgramFileError, match="empty|not a ROS 2 bag"):
            read_joint_states_bytes(upload, NAMES, FINGERS_M)


def test_an_uploaded_bag_reads_as_a_file_or_a_zip(tmp_path):
    import io
    import zipfile

    bag = write_joint_bag(tmp_path / "pick", pick_rows(), storage="sqlite3")
    bare = read_joint_states_bytes(next(bag.glob("*.db3")).read_bytes(), NAMES, FINGERS_M)
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for file in bag.iterdir():
            archive.write(file, f"pick/{file.name}")
    zipped = read_joint_states_bytes(buffer.getvalue(), NAMES, FINGERS_M)
    assert np.array_equal(bare.positions_rad, zipped.positions_rad) and bare.gripper == zipped.gripper
    assert len(bare.gripper) == 400


def test_the_courses_timed_lines_and_rows_of_five_angles():
    timed = "\n".join([
        "# t, [q1..q5, gripper]",
        "0.0, [0.0, -0.3, 0.3, 0.9, 0.0, 0]",
        "0.5, [0.0, -0.3, 0.3, 0.9, 0.0, 0]",
        "2.0, [0.45, 0.05, 0.35, 1.0, 0.0, 0]",
        "2.0, [0.45, 0.05, 0.35, 1.0, 0.0, 1]",
        "3.5, [0.9, 0.2, 0.1, 1.1, 0.3, 1]",
    ])
    got = _convert(parse_jointdata(timed, 5)).waypoints
    assert [(w.joints_rad, w.gripper) for w in got] == [(POSE_A, "release"), (POSE_B, "release"), (POSE_B, "grasp"), (POSE_C, "grasp")]
    assert got[0].dwell_s == pytest.approx(0.5) and got[1].moving_time_s == pytest.approx(1.5)
    rows = "\n".join([
        "[ 0.   -0.3   0.3   0.9   0.  ]",
        "[ 0.45  0.05  0.35  1.0   0.  ]",
        "Close",
        "Close",
        "[ 0.45  0.05  0.35  1.0   0.  ]",
        "[ 9.00000000e-01  2.00000000e-01  1.00000000e-01  1.10000000e+00  3.00000000e-01]",
        "Open",
        "[ 9.00000000e-01  2.00000000e-01  1.00000000e-01",  # numpy wraps a long row
        "  1.10000000e+00  3.00000000e-01]",
    ])
    got = _convert(parse_jointdata(rows, 5)).waypoints
    assert [(w.joints_rad, w.gripper) for w in got] == [
        (POSE_A, "release"), (POSE_B, "release"), (POSE_B, "grasp"), (POSE_C, "grasp"), (POSE_C, "release")]
    assert all(w.moving_time_s is None and w.dwell_s == 0.0 for w in got)  # untimed rows: as fast as allowed


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "no joint rows"),
        ("[0.1 0.2 0.3 0.4]", "line 1: 4 values; expected 5"),
        ("0.0, [0, 0, 0, 0, 0, 0]\n[0 0 0 0 0]", "line 2: an untimed line in a file of timed lines"),
        ("1.0, [0, 0, 0, 0, 0, 0]\n0.5, [0, 0, 0, 0, 0, 0]", "line 2: t = 0.5 goes back in time"),
        ("0.0, [0, 0, 0, 0, 0, 7]", "line 1: gripper = 7"),
        ("[0 0 abc 0 0]", "line 1: value 3 = 'abc' is not a number"),
        ("\x89MCAP0\r\n\x00\x01", "line 1"),
        ("[0 0 0 0 0]\n[0.1 0.2\n", "line 2: the bracket opened here is never closed"),
    ],
)
def test_malformed_course_text_is_refused_naming_the_line(text, message):
    with pytest.raises(ProgramFileError, match=message):
        parse_jointdata(text, 5)


def test_bad_options_are_refused():
    with pytest.raises(ProgramFileError, match="mode must be one of"):
        ImportOptions(mode="spline")
    with pytest.raises(ProgramFileError, match="clamp_rad must be from 0 to 1"):
        ImportOptions(clamp_rad=-0.1)


def test_the_fingers_threshold_sits_between_open_and_a_held_block():
    assert FINGERS_M[1] - 0.25 * (FINGERS_M[1] - FINGERS_M[0]) < OPEN_M and HOLDING_M < FINGERS_M[1] - 0.25 * (FINGERS_M[1] - FINGERS_M[0])
