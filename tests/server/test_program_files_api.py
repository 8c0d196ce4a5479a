"""Program files over real HTTP (issue 23 item 4): a ROS 2 bag written by `rosbags` uploads as a program of its
poses; a program downloads as a bag (one MCAP file) that uploads back to the same waypoints; bad uploads
(no joint states, other names, beyond the limits without clamp_rad, truncated, the wrong format) are 422 with
nothing stored; an upload needs the control token."""

from __future__ import annotations

import httpx
import pytest

import live
from joint_bag_helpers import POSE_A, POSE_B, POSE_C, pick_rows, write_joint_bag

TOKEN = "bags-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
BINARY = {**AUTH, "Content-Type": "application/octet-stream"}
PICK = [(list(POSE_A), "release"), (list(POSE_B), "release"), (list(POSE_B), "grasp"), (list(POSE_C), "grasp")]

cell, url = live.module_fixtures(seed=5, token=TOKEN, time_scale=live.FAST_TIME_SCALE)


@pytest.fixture()
def http(url):
    with httpx.Client(base_url=url, timeout=60.0) as client:
        yield client


def _mcap(folder):
    return next(folder.glob("*.mcap")).read_bytes()


def _stored(http) -> list[int]:
    return [p["id"] for p in http.get("/api/programs").json()["data"]]


def test_upload_a_bag_download_it_as_a_bag_and_upload_it_back(http, tmp_path):
    data = _mcap(write_joint_bag(tmp_path / "pick", pick_rows()))
    response = http.post("/api/programs/import/file", params={"format": "rosbag2", "name": "real pick"}, content=data, headers=BINARY)
    assert response.status_code == 201, response.text
    program = response.json()
    assert [(w["joints_rad"], w["gripper"]) for w in program["waypoints"]] == PICK
    assert program["samples"] == 400 and program["clamped_samples"] == 0 and any("4 waypoints" in n for n in program["notes"])

    download = http.get(f"/api/programs/{program['id']}/export", params={"format": "rosbag2"})
    assert download.status_code == 200 and download.headers["content-type"] == "application/octet-stream"
    assert download.headers["content-disposition"] == 'attachment; filename="real_pick.mcap"'
    assert download.content.startswith(b"\x89MCAP0\r\n")
    back = http.post("/api/programs/import/file", params={"format": "rosbag2"}, content=download.content, headers=BINARY)
    assert back.status_code == 201, back.text
    assert [(w["joints_rad"], w["gripper"]) for w in back.json()["waypoints"]] == PICK
    assert [w["dwell_s"] for w in back.json()["waypoints"]] == pytest.approx([w["dwell_s"] for w in program["waypoints"]], abs=1e-6)

    text = b"0.0, [0.0, -0.3, 0.3, 0.9, 0.0, 0]\n2.0, [0.45, 0.05, 0.35, 1.0, 0.0, 0]\n2.0, [0.45, 0.05, 0.35, 1.0, 0.0, 1]\n"
    course = http.post("/api/programs/import/file", params={"format": "jointdata", "name": "course"}, content=text, headers=BINARY)
    assert course.status_code == 201, course.text
    assert [(w["joints_rad"], w["gripper"]) for w in course.json()["waypoints"]] == PICK[:3]


def test_bad_uploads_are_refused_with_nothing_stored(http, tmp_path):
    over = [(t, [q[0], 2.5 if q[:5] == list(POSE_B) else q[1], *q[2:]]) for t, q in pick_rows()]
    whole = _mcap(write_joint_bag(tmp_path / "whole", pick_rows()))
    cases = [
        ({"format": "rosbag2"}, _mcap(write_joint_bag(tmp_path / "none", None)), "no sensor_msgs/msg/JointState topic"),
        ({"format": "rosbag2"}, _mcap(write_joint_bag(tmp_path / "ur", [(0.0, [0.0] * 6)], names=[f"j{i}" for i in range(6)])), "not this arm's"),
        ({"format": "rosbag2"}, _mcap(write_joint_bag(tmp_path / "over", over)), "joint 'shoulder' = 2.5000 rad is outside its limits"),
        ({"format": "rosbag2", "clamp_rad": 0.1}, _mcap(tmp_path / "over"), "more than the 0.1 rad clamp allows"),
        ({"format": "rosbag2"}, whole[: len(whole) // 2], "not a readable ROS 2 bag|damaged or truncated"),
        ({"format": "rosbag2"}, b"", "body: Field required"),  # FastAPI refuses an empty body before the route
        ({"format": "csv"}, whole, "not UTF-8 text"),
        ({"format": "jointdata"}, b"0.0, [0, 0, 0]\n", "line 1: 3 values"),
    ]
    before = _stored(http)
    for params, content, reason in cases:
        response = http.post("/api/programs/import/file", params=params, content=content, headers=BINARY)
        assert response.status_code == 422, (params, response.text)
        assert response.json()["error"]["code"] == "invalid"
        assert __import__("re").search(reason, response.json()["error"]["message"]), (params, response.text)
        assert _stored(http) == before
    wrong = http.post("/api/programs/import/file", params={"format": "rosbag1"}, content=whole, headers=BINARY)
    assert wrong.status_code == 422 and _stored(http) == before
    anonymous = http.post("/api/programs/import/file", params={"format": "rosbag2"}, content=whole,
                          headers={"Content-Type": "application/octet-stream"})
    assert anonymous.status_code == 401 and _stored(http) == before


def test_the_repeats_cycle_trace_downloads_as_a_bag(http, tmp_path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    rows = [(0.0, POSE_A, "release"), (1.0, POSE_B, "release")]
    text = "".join(f"{t}, [{', '.join(map(str, q))}, 0]\n" for t, q, _ in rows).encode()
    program = http.post("/api/programs/import/file", params={"format": "jointdata", "name": "two"}, content=text, headers=BINARY).json()
    job = http.post(f"/api/programs/{program['id']}/repeat", params={"wait": "true"}, json={"cycles": 1}, headers=AUTH, timeout=120)
    assert job.status_code == 200 and job.json()["job"]["state"] == "succeeded", job.text
    trace = http.get("/api/jobs/current/trace").json()
    download = http.get("/api/jobs/current/trace", params={"format": "rosbag2"})
    assert download.status_code == 200 and download.headers["content-type"] == "application/octet-stream"
    path = tmp_path / "trace.mcap"
    path.write_bytes(download.content)
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        measured = [list(reader.deserialize(raw, c.msgtype).position)
                    for c, _, raw in reader.messages(connections=[c for c in reader.connections if c.topic == "/rx200/joint_states"])]
    assert counts == {"/rx200/joint_states": len(trace["samples"]), "/rx200/commanded/joint_states": len(trace["samples"])}
    assert measured == [row[6:11] for row in trace["samples"]]
