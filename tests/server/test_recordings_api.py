"""Recordings over real HTTP on the real-time simulation (issue 23 item 2): a recording made through the API holds
every channel of armlab.recording.TOPICS with Foxglove's schema and ordered times, read with the `mcap` reader; the
recorded joints are exactly what the arm reported to the station; a second start is a 409 and the first goes on;
stop, list, download and delete; bad ids are 404; mutating needs the token."""

from __future__ import annotations

import httpx
import numpy as np
import pytest
from mcap.reader import make_reader

import live
from armlab.recording import TOPICS, iter_messages, summarize
from armlab.recording.library import RecordingLibrary
from armlab.station.config import RecordingConfig

TOKEN = "recordings-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
MAGIC = b"\x89MCAP0\r\n"

cell, url = live.module_fixtures(seed=5, token=TOKEN)


@pytest.fixture
def http(url):
    with httpx.Client(base_url=url, timeout=30, headers=AUTH) as client:
        yield client
        if client.get("/api/recordings").json()["active"] is not None:
            client.post("/api/recordings/stop")


def active_topics(http) -> dict:
    active = http.get("/api/recordings").json()["active"]
    return active["topics"] if active else {}


def test_a_recording_has_every_channel_with_its_schema_and_times_in_order(http, tmp_path):
    started = http.post("/api/recordings/start", json={"label": "channels"})
    assert started.status_code == 201, started.text
    recording_id = started.json()["recording"]["id"]
    home = http.get("/api/status").json()["joints_rad"]
    target = [home[0] + 0.3, *home[1:]]
    assert http.post("/api/arm/joints?wait=true", json={"q_rad": target, "moving_time_s": 1.0}).status_code == 200
    live.wait_for(lambda: all(active_topics(http).get(topic, 0) >= 2 for topic in TOPICS if topic != "/camera/calibration")
                  and active_topics(http)["/joint_states"] >= 60, 60)
    assert http.post("/api/arm/joints?wait=true", json={"q_rad": home, "moving_time_s": 1.0}).status_code == 200
    assert http.post("/api/teach/start", json={"discard_draft": True}).status_code == 200  # a teach session in it too
    live.wait_for(lambda: "teach" in http.get("/api/recordings").json()["active"]["states"], 30)
    assert http.post("/api/teach/exit").status_code == 200
    stopped = http.post("/api/recordings/stop")
    assert stopped.status_code == 200, stopped.text
    info = stopped.json()["recording"]
    assert info["id"] == recording_id and info["complete"] and info["label"] == "channels"
    assert info["states"] == ["idle", "teach"]  # what the station did while it recorded
    download = http.get(f"/api/recordings/{recording_id}")
    assert download.status_code == 200 and download.content.startswith(MAGIC)
    assert len(download.content) == info["size_bytes"]
    path = tmp_path / f"{recording_id}.mcap"
    path.write_bytes(download.content)

    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        schemas = {channel.topic: summary.schemas[channel.schema_id].name for channel in summary.channels.values()}
        assert schemas == TOPICS
        last: dict[str, int] = {}
        for _, channel, message in reader.iter_messages(log_time_order=False):
            assert message.log_time >= last.get(channel.topic, 0), channel.topic
            last[channel.topic] = message.log_time
    assert set(last) == set(TOPICS)  # every channel has messages
    header_times = [m.timestamp.seconds * 10**9 + m.timestamp.nanos for _, _, _, m in iter_messages(path, {"/joint_states"})]
    assert all(a < b for a, b in zip(header_times, header_times[1:])) and len(header_times) >= 60
    commanded = [m for _, _, _, m in iter_messages(path, {"/joint_commands"})]
    assert max(j.position for m in commanded for j in m.joints if j.name == "waist") == pytest.approx(target[0], abs=1e-6)
    transforms = {t.child_frame_id for _, _, _, m in iter_messages(path, {"/tf"}) for t in m.transforms}
    assert {"base", "waist", "gripper"} <= transforms
    calibration = next(m for _, _, _, m in iter_messages(path, {"/camera/calibration"}))
    assert calibration.K[0] > 0 and calibration.width > 0 and calibration.frame_id == "camera"
    image = next(m for _, _, _, m in iter_messages(path, {"/camera/color/compressed"}))
    assert image.format == "jpeg" and bytes(image.data[:2]) == b"\xff\xd8"
    logs = [m.message for _, _, _, m in iter_messages(path, {"/events"})]
    assert any(f"recording {recording_id} started" in text for text in logs) and "state: idle -> teach" in logs


def test_recorded_joints_are_what_the_arm_reported(cell, tmp_path):
    """The station's own readings, spied on: every recorded joint state is one of them, exactly, names in order."""
    station = live.make_station(cell, tmp_path / "spy.sqlite3")
    reported: dict[int, np.ndarray] = {}
    read = station.arm.read_joint_state

    def spy():
        reading = read()
        reported[round(reading.timestamp_s * 1e9)] = np.array(reading.position_rad, dtype=float)
        return reading

    station.arm.read_joint_state = spy
    try:
        library = RecordingLibrary(tmp_path / "recordings", RecordingConfig(camera_rate_hz=0, depth_rate_hz=0))
        library.start(station)
        station.move_joints(np.asarray(station.model.home_rad) + [0.2, 0.1, -0.1, 0.1, 0.3], moving_time_s=0.6, wait=False)
        live.wait_for(lambda: library.active()["topics"].get("/joint_states", 0) >= 150, 30)
        info = library.stop()
    finally:
        station.arm.read_joint_state = read
        station.close()
    recorded = [m for _, _, _, m in iter_messages(library.path(info["id"]), {"/joint_states"})]
    assert len(recorded) >= 150
    moved = 0
    for message in recorded:
        assert [joint.name for joint in message.joints] == list(station.model.joint_names)
        stamp_ns = message.timestamp.seconds * 10**9 + message.timestamp.nanos
        assert stamp_ns in reported, "a recorded joint state the arm never reported"
        assert [joint.position for joint in message.joints] == reported[stamp_ns].tolist()
        moved += not np.allclose(reported[stamp_ns], station.model.home_rad)
    assert moved > 10  # the motion is in it, not only the rest before it


def test_start_twice_is_a_409_and_the_first_recording_goes_on(http):
    first = http.post("/api/recordings/start").json()["recording"]
    second = http.post("/api/recordings/start")
    assert second.status_code == 409 and "already recording" in second.json()["error"]["message"]
    size = http.get("/api/recordings").json()["active"]["size_bytes"]
    live.wait_for(lambda: http.get("/api/recordings").json()["active"]["size_bytes"] > size, 30)
    listing = http.get("/api/recordings").json()
    assert listing["active"]["id"] == first["id"]
    assert http.get(f"/api/recordings/{first['id']}").status_code == 409  # still being written
    assert http.delete(f"/api/recordings/{first['id']}").status_code == 409
    stopped = http.post("/api/recordings/stop").json()["recording"]
    assert stopped["id"] == first["id"] and stopped["complete"] and stopped["size_bytes"] > size
    again = http.post("/api/recordings/stop")
    assert again.status_code == 409 and "nothing is recording" in again.json()["error"]["message"]
    listed = {item["id"]: item for item in http.get("/api/recordings").json()["data"]}
    assert listed[first["id"]]["duration_s"] > 0 and listed[first["id"]]["topics"]["/joint_states"] > 0
    assert http.delete(f"/api/recordings/{first['id']}").json() == {"deleted": first["id"]}
    assert first["id"] not in {item["id"] for item in http.get("/api/recordings").json()["data"]}


@pytest.mark.parametrize("bad", ["nothing-here", "20261201T000000Z-aaaaaa", "20261201T000000Z-aaaaaa.json", "20261201T000000Z-AAAAAA"])
def test_bad_ids_are_404(http, bad):
    assert http.get(f"/api/recordings/{bad}").status_code == 404
    assert http.delete(f"/api/recordings/{bad}").status_code == 404


def test_mutating_needs_the_token(url):
    for method, path in (("POST", "/api/recordings/start"), ("POST", "/api/recordings/stop"),
                         ("DELETE", "/api/recordings/20261201T000000Z-aaaaaa")):
        assert httpx.request(method, url + path, timeout=10).status_code == 401


def test_the_recording_stops_with_the_station_complete(cell, tmp_path):
    """Shutting the server down mid-recording closes the file with its summary."""
    from server.app import create_app

    app = create_app(station_factory=lambda: live.StationOnCell(cell, tmp_path / "db.sqlite3"), token=TOKEN,
                     recordings_dir=tmp_path / "recs")
    with live.serve(app) as base:
        assert httpx.post(base + "/api/recordings/start", headers=AUTH, timeout=30).status_code == 201
        live.wait_for(lambda: httpx.get(base + "/api/recordings", timeout=10).json()["active"]["topics"].get("/joint_states", 0) > 10)
    (path,) = (tmp_path / "recs").glob("*.mcap")
    summary = summarize(path)
    assert summary.complete and summary.topics["/joint_states"]["count"] > 10

