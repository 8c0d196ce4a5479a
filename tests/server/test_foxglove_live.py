"""Live in Foxglove (issue 23 item 1): a real `armlab serve --foxglove PORT` subprocess on the simulation, and a
WebSocket client speaking Foxglove's protocol (foxglove_ws.py): the server is view-only and advertises every channel
of the recording with its Foxglove schema; joint states match GET /api/status; /tf carries the URDF's links, which
compose to the arm's own gripper frame; the colour (JPEG), depth and calibration agree; detections arrive as scene
entities once calibrated; state changes and jobs arrive as logs; the URDF asset names the arm's joints and the meshes it names
are served (nothing else is); it listens on loopback only. And `armlab serve` refuses a bad port, a port in use and
a non-loopback host without --foxglove-allow-remote, in one line each."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import xml.etree.ElementTree as ET

import httpx
import numpy as np
import psutil
import pytest

import live
from armlab.recording import TOPICS
from armlab.recording.live import MESH_DIR, URDF_URI
from foxglove_ws import FoxgloveClient

TOKEN = "foxglove-live-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
GOAL_RAD = [0.35, -0.25, 0.3, 0.45, -0.6]  # a pose unlike home: joint order or values mixed up would show


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    folder = tmp_path_factory.mktemp("foxglove")
    port = live.free_port()
    process, base = live.start_serve_process(TOKEN, folder / "station.sqlite3", live.serve_config(folder), "--foxglove", str(port))
    try:
        yield process, base, port
    finally:
        process.terminate()
        try:
            process.wait(20)
        except subprocess.TimeoutExpired:
            process.kill()


@pytest.fixture()
def client(served):
    with FoxgloveClient(f"ws://127.0.0.1:{served[2]}") as connected:
        yield connected


@pytest.fixture()
def http(served):
    with httpx.Client(base_url=served[1], timeout=60.0) as session:
        if session.get("/api/status").json()["state"] != "idle":
            session.post("/api/reset", headers=AUTH)
        yield session


def test_view_only_server_advertises_every_channel_with_its_schema(client, served):
    assert client.info["capabilities"] == ["assets"]  # no client publishing, services or parameters: nothing reaches the station
    channels = client.topics(TOPICS)
    assert {topic: channel["schemaName"] for topic, channel in channels.items()} == TOPICS
    for topic, channel in channels.items():
        if TOPICS[topic].startswith("foxglove."):
            assert channel["encoding"] == "protobuf" and channel["schemaEncoding"] == "protobuf" and channel["schema"], topic
        else:
            assert channel["encoding"] == "json" and channel["schemaEncoding"] == "jsonschema", topic
    listening = [c for c in psutil.Process(served[0].pid).net_connections() if c.status == "LISTEN" and c.laddr.port == served[2]]
    assert listening and all(c.laddr.ip == "127.0.0.1" for c in listening)


def test_joint_states_are_the_stations(client, http):
    moved = http.post("/api/arm/joints", params={"wait": "true"}, json={"q_rad": GOAL_RAD, "moving_time_s": 1.0}, headers=AUTH)
    assert moved.status_code == 200, moved.text
    live.wait_for(lambda: not http.get("/api/status").json()["moving"], 20)
    client.subscribe(["/joint_states", "/joint_commands"])
    measured, _ = client.next_message("/joint_states")
    status = http.get("/api/status").json()
    assert [joint.name for joint in measured.joints] == status["joint_names"]
    assert np.allclose([joint.position for joint in measured.joints], status["joints_rad"], atol=2e-3)
    assert np.allclose(status["joints_rad"], GOAL_RAD, atol=0.02)
    commanded, _ = client.next_message("/joint_commands")
    assert np.allclose([joint.position for joint in commanded.joints], GOAL_RAD, atol=1e-6)


def _pose(transform) -> np.ndarray:
    q, t = transform.rotation, transform.translation
    x, y, z, w = q.x, q.y, q.z, q.w
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = [t.x, t.y, t.z]
    return T


def test_transforms_carry_the_urdf_links(client):
    client.subscribe(["/tf"])
    message, _ = client.next_message("/tf")
    by_child = {t.child_frame_id: t for t in message.transforms}
    assert {"base", "waist", "gripper", "waist_link", "wrist_rotate_link", "tool_point", "left_finger_link"} <= set(by_child)
    frame, chain = "tool_point", []
    while frame != "world":  # the URDF's links, each from its parent, compose to the arm model's gripper point
        chain.append(by_child[frame])
        frame = by_child[frame].parent_frame_id
    T = np.eye(4)
    for transform in reversed(chain):
        T = T @ _pose(transform)
    assert np.allclose(T, _pose(by_child["gripper"]), atol=1e-6)


def test_camera_images_and_calibration_agree(client):
    client.subscribe(["/camera/color/compressed", "/camera/depth", "/camera/calibration"])
    colour, _ = client.next_message("/camera/color/compressed", 20)
    assert colour.format == "jpeg" and colour.data[:2] == b"\xff\xd8" and colour.frame_id == "camera"
    calibration, _ = client.next_message("/camera/calibration", 20)
    assert calibration.K[0] > 0 and calibration.distortion_model == "plumb_bob"
    depth, _ = client.next_message("/camera/depth", 20)
    assert depth.encoding == "16UC1" and (depth.width, depth.height) == (calibration.width, calibration.height)
    assert len(depth.data) == depth.step * depth.height and depth.step == 2 * depth.width


def test_state_changes_arrive_as_logs(client, http):
    client.subscribe(["/events"])
    assert http.post("/api/estop").json()["state"] == "estop"
    texts = []
    live.wait_for(lambda: texts.append(client.next_message("/events")[0]) or any(m.message == "state: idle -> estop" for m in texts), 20, 0)
    assert next(m for m in texts if m.message == "state: idle -> estop").name == "state"
    assert http.post("/api/reset", headers=AUTH).json()["state"] == "idle"


def test_detections_arrive_as_scene_entities_once_calibrated_and_jobs_as_logs(client, http):
    client.subscribe(["/events"])
    events_id = client.topics(["/events"])["/events"]["id"]
    calibrated = http.post("/api/calibrate", params={"wait": "true"}, headers=AUTH)
    assert calibrated.status_code == 200 and calibrated.json()["job"]["state"] == "succeeded", calibrated.text

    def job_logs() -> list[str]:
        return [text for text in (client.decode(m[0], m[2]).message for m in client.messages if m[0] == events_id) if text.startswith("job 'calibrate'")]

    client._until(lambda: len(job_logs()) >= 2, 20)  # its start and its end, from the station's event log
    assert job_logs()[0].startswith("job 'calibrate' started") and job_logs()[1].startswith("job 'calibrate' succeeded")
    client.subscribe(["/detections/scene", "/tf"])
    found = []

    def with_blocks():
        update, _ = client.next_message("/detections/scene", 20)
        found.append(update)
        return update.entities

    entities = live.wait_for(with_blocks, 60, 0)
    assert all(entity.frame_id == "world" and entity.cubes and entity.id.startswith("block-") for entity in entities)
    assert found[-1].deletions and found[-1].deletions[0].type == 1  # ALL: blocks no longer seen disappear
    transforms, _ = client.next_message("/tf")
    assert "camera" in {t.child_frame_id for t in transforms.transforms}


def test_urdf_asset_names_the_arm_and_its_meshes_are_served(client, http):
    status, error, data = client.fetch_asset(URDF_URI)
    assert status == 0, error
    robot = ET.fromstring(data)
    joints = {joint.get("name") for joint in robot.iter("joint")}
    assert set(http.get("/api/status").json()["joint_names"]) <= joints
    meshes = sorted({mesh.get("filename") for mesh in robot.iter("mesh")})
    assert meshes and all(name.startswith("package://armlab/meshes/rx200/") for name in meshes)
    status, error, data = client.fetch_asset(meshes[0])
    assert status == 0 and data == (MESH_DIR / "rx200" / meshes[0].rsplit("/", 1)[1]).read_bytes()
    for other in ("package://armlab/meshes/rx200/../../../README.md", "package://armlab/meshes/rx200/LICENSE",
                  "package://armlab/urdf/other.urdf", "file:///etc/passwd"):
        assert client.fetch_asset(other)[0] == 1, other


def _serve(*args: str) -> subprocess.CompletedProcess:
    env = {key: value for key, value in os.environ.items() if key != "ARMLAB_TOKEN"}
    return subprocess.run([sys.executable, "-m", "armlab.cli", "serve", "--port", str(live.free_port()), *args], cwd=live.REPO,
                          env=env, capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize(("args", "says"), [
    (("--foxglove", "70000"), "--foxglove 70000: a port is a whole number from 1 to 65535"),
    (("--foxglove", "8765", "--foxglove-host", "0.0.0.0"), "--foxglove-allow-remote"),
    (("--foxglove-host", "192.168.1.5"), "only with --foxglove"),
])
def test_serve_refuses_a_bad_port_or_a_public_host(args, says):
    done = _serve(*args)
    assert done.returncode == 2 and says in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr


def test_serve_refuses_a_port_in_use(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = _serve("--foxglove", str(port), "--db", str(tmp_path / "db.sqlite3"))
    assert done.returncode == 2 and f"cannot listen on 127.0.0.1:{port}" in done.stderr, done.stderr
