"""`armlab programs list|import|export` on a station database (issue 23 item 4): a bag written by `rosbags`
imports as a program of the written poses; export then re-import round-trips (ROS 2 bag as MCAP file and as a
sqlite3 folder, CSV, JSON, and the course's text); every bad input exits 1 saying why with nothing stored."""

from __future__ import annotations

import json
import math

import pytest

from armlab.cli import main
from armlab.store import Store, Waypoint
from joint_bag_helpers import POSE_A, POSE_B, POSE_C, RX200_NAMES, pick_rows, write_joint_bag

PICK = [(POSE_A, "release"), (POSE_B, "release"), (POSE_B, "grasp"), (POSE_C, "grasp")]


def _run(capsys, *argv) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def _programs(db):
    return Store(db).list_programs()


def test_import_list_export_and_reimport_round_trip(tmp_path, capsys):
    db = str(tmp_path / "station.sqlite3")
    bag = write_joint_bag(tmp_path / "pick_bag", pick_rows())
    code, out, err = _run(capsys, "programs", "import", str(bag), "--db", db, "--name", "real pick")
    assert code == 0, err
    assert "400 samples -> 4 waypoints" in out and "stored program 1 'real pick': 4 waypoints" in out
    imported = _programs(db)[0]
    assert [(w.joints_rad, w.gripper) for w in imported.waypoints] == PICK

    code, out, _ = _run(capsys, "programs", "list", "--db", db)
    assert code == 0 and "1  real pick  (4 waypoints" in out
    code, out, _ = _run(capsys, "programs", "list", "--db", db, "--json")
    assert json.loads(out)["programs"][0] == {**json.loads(out)["programs"][0], "id": 1, "name": "real pick", "waypoints": 4}

    for fmt, out_name, extra in (("rosbag2", "pick.mcap", []), ("rosbag2", "pick_sqlite", ["--storage", "sqlite3"]),
                                 ("csv", "pick.csv", []), ("json", "pick.json", [])):
        target = tmp_path / out_name
        code, _, err = _run(capsys, "programs", "export", "1", "--format", fmt, "--out", str(target), "--db", db, *extra)
        assert code == 0, err
        if out_name == "pick_sqlite":
            assert sorted(p.suffix for p in target.iterdir()) == [".db3", ".yaml"]
        code, _, err = _run(capsys, "programs", "import", str(target), "--db", db, "--name", f"back {out_name}")
        assert code == 0, err
        back = _programs(db)[-1]
        assert back.name == f"back {out_name}"
        assert [(w.joints_rad, w.gripper) for w in back.waypoints] == [(w.joints_rad, w.gripper) for w in imported.waypoints]
        assert [w.dwell_s for w in back.waypoints] == pytest.approx([w.dwell_s for w in imported.waypoints], abs=1e-6)
        for got, want in zip(back.waypoints[1:], imported.waypoints[1:]):  # the export's move times: at least the recorded ones
            assert (got.moving_time_s is None) == (want.moving_time_s is None)
            assert got.moving_time_s is None or got.moving_time_s >= want.moving_time_s - 1e-6
    code, _, err = _run(capsys, "programs", "export", "1", "--format", "csv", "--out", str(tmp_path / "pick.csv"), "--db", db)
    assert code == 1 and "exists already" in err


def test_a_zipped_bag_folder_imports(tmp_path, capsys):
    import zipfile

    db = str(tmp_path / "station.sqlite3")
    bag = write_joint_bag(tmp_path / "pick", pick_rows(), storage="sqlite3")
    with zipfile.ZipFile(tmp_path / "pick.zip", "w") as archive:
        for file in bag.iterdir():
            archive.write(file, f"pick/{file.name}")
    code, out, err = _run(capsys, "programs", "import", str(tmp_path / "pick.zip"), "--db", db)
    assert code == 0, err
    program = _programs(db)[0]
    assert program.name == "pick" and [(w.joints_rad, w.gripper) for w in program.waypoints] == PICK


def test_the_courses_text_imports(tmp_path, capsys):
    db = str(tmp_path / "station.sqlite3")
    text = tmp_path / "recordedPath.txt"
    text.write_text("[ 0.   -0.3   0.3   0.9   0.  ]\n[ 0.45  0.05  0.35  1.0   0.  ]\nClose\n[ 0.45  0.05  0.35  1.0   0.  ]\n"
                    "[ 0.9  0.2  0.1  1.1  0.3]\n")
    code, out, err = _run(capsys, "programs", "import", str(text), "--db", db)
    assert code == 0, err
    program = _programs(db)[0]
    assert program.name == "recordedPath" and [(w.joints_rad, w.gripper) for w in program.waypoints] == PICK


def _bad_bags(tmp_path):
    over = [(t, [q[0], 2.5 if q[:5] == list(POSE_B) else q[1], *q[2:]]) for t, q in pick_rows()]  # shoulder beyond 113°
    ur3 = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
    cut = tmp_path / "cut.mcap"
    data = next(write_joint_bag(tmp_path / "whole", pick_rows()).glob("*.mcap")).read_bytes()
    cut.write_bytes(data[: len(data) * 2 // 3])
    (tmp_path / "empty.mcap").write_bytes(b"")
    return [
        ([str(write_joint_bag(tmp_path / "no_joints", None))], "no sensor_msgs/msg/JointState topic"),
        ([str(write_joint_bag(tmp_path / "ur3", [(0.0, [0.0] * 6)], names=ur3))], "not this arm's"),
        ([str(write_joint_bag(tmp_path / "counts", [(0.0, [0.0] * 7)], names=RX200_NAMES))], "8 joint names but 7 positions"),
        ([str(write_joint_bag(tmp_path / "over", over))], "joint 'shoulder' = 2.5000 rad is outside its limits"),
        ([str(tmp_path / "over"), "--clamp", "0.1"], "more than the 0.1 rad clamp allows"),
        ([str(write_joint_bag(tmp_path / "table", pick_rows(pose_b=(0.0, 1.9, 1.6, 0.0, 0.0))))], "waypoint 2: .*below the board"),
        ([str(tmp_path / "empty.mcap")], "empty"),
        ([str(cut)], "not a readable ROS 2 bag|damaged or truncated"),
        ([str(tmp_path / "whole"), "--format", "csv"], "is a folder, not a csv file"),
        ([str(cut), "--format", "json"], "not UTF-8 text, so not a json file"),
        ([str(cut), "--format", "jointdata"], "not UTF-8 text"),
    ]


def test_bad_inputs_exit_1_saying_why_and_store_nothing(tmp_path, capsys):
    db = str(tmp_path / "station.sqlite3")
    Store(db).save_program("kept", [Waypoint(POSE_A, "release")])
    for args, message in _bad_bags(tmp_path):
        code, _, err = _run(capsys, "programs", "import", *args, "--db", db)
        assert code == 1, (args, err)
        assert err.startswith("armlab programs import: ") and __import__("re").search(message, err), (args, err)
        assert [p.name for p in _programs(db)] == ["kept"]
    with pytest.raises(SystemExit) as exit_info:  # a format that does not exist: argparse refuses it
        main(["programs", "import", str(tmp_path / "over"), "--format", "rosbag1", "--db", db])
    assert exit_info.value.code == 2 and "invalid choice: 'rosbag1'" in capsys.readouterr().err
    code, _, err = _run(capsys, "programs", "import", str(tmp_path / "file.xyz"), "--db", db)
    assert code == 1 and "cannot tell its format" in err
    code, _, err = _run(capsys, "programs", "export", "99", "--format", "rosbag2", "--out", str(tmp_path / "x.mcap"), "--db", db)
    assert code == 1 and "no program with id 99" in err and not (tmp_path / "x.mcap").exists()
    assert [p.name for p in _programs(db)] == ["kept"]


def test_clamping_is_said_and_only_by_the_amount_asked(tmp_path, capsys):
    db = str(tmp_path / "station.sqlite3")
    over_c = (*POSE_C[:4], math.pi + 0.0175)  # wrist_rotate 1° beyond its 180° limit at C
    bag = write_joint_bag(tmp_path / "over", pick_rows(pose_c=over_c))
    code, _, err = _run(capsys, "programs", "import", str(bag), "--db", db)
    assert code == 1 and "joint 'wrist_rotate' = 3.1591 rad is outside its limits" in err and _programs(db) == []
    code, out, err = _run(capsys, "programs", "import", str(bag), "--db", db, "--clamp", "0.02")
    assert code == 0, err
    assert "clamped" in out and "wrist_rotate by up to 0.0175 rad" in out
    assert _programs(db)[0].waypoints[-1].joints_rad == pytest.approx((*POSE_C[:4], math.pi))
