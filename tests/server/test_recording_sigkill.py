"""SIGKILL a real `armlab serve` (simulation) while it records (issue 23 item 2): the MCAP file it leaves is readable
with the `mcap` library up to its last complete chunk, and holds at least every message the station had recorded a
flush before the kill; the next station lists it as truncated, cut short."""

from __future__ import annotations

import signal
import subprocess
from pathlib import Path

import httpx
import yaml
from mcap.exceptions import McapError
from mcap.records import Channel, Message, Schema
from mcap.stream_reader import StreamReader

import live
from armlab.recording import RecordingLibrary

TOKEN = "recording-sigkill-token"
AUTH = {"Authorization": f"Bearer {TOKEN}"}
FLUSH_INTERVAL_S = 0.2


def _start(folder: Path) -> tuple[subprocess.Popen, str]:
    config_path = Path(live.serve_config(folder))
    config = yaml.safe_load(config_path.read_text())
    config["recording"] = {**config.get("recording", {}), "flush_interval_s": FLUSH_INTERVAL_S, "chunk_size_kb": 65536}  # only the flush closes chunks
    config_path.write_text(yaml.safe_dump(config))
    return live.start_serve_process(TOKEN, folder / "station.sqlite3", config_path, "--recordings", str(folder / "recordings"))


def _read_with_mcap(path: Path) -> tuple[dict[str, int], dict[str, str], str | None]:
    """Messages per topic and schema per topic, read with the mcap library's stream reader up to the damage."""
    counts: dict[str, int] = {}
    schemas: dict[int, str] = {}
    channels: dict[int, tuple[str, str]] = {}
    damage = None
    with open(path, "rb") as stream:
        try:
            for record in StreamReader(stream, validate_crcs=True).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record.name
                elif isinstance(record, Channel):
                    channels[record.id] = (record.topic, schemas.get(record.schema_id, ""))
                elif isinstance(record, Message):
                    topic = channels[record.channel_id][0]
                    counts[topic] = counts.get(topic, 0) + 1
        except (McapError, EOFError) as error:
            damage = f"{type(error).__name__}: {error}"
    return counts, dict(channels.values()), damage


def test_sigkill_mid_recording_leaves_a_file_readable_to_its_last_chunk(tmp_path):
    process, base = _start(tmp_path)
    try:
        started = httpx.post(base + "/api/recordings/start", json={"label": "killed"}, headers=AUTH, timeout=30)
        assert started.status_code == 201, started.text
        recording_id = started.json()["recording"]["id"]

        def active() -> dict:
            return httpx.get(base + "/api/recordings", timeout=10).json()["active"]

        live.wait_for(lambda: active()["topics"].get("/camera/color/compressed", 0) >= 5, 60)
        before = active()  # what the station had recorded; a flush later it is all on disk
        size = before["size_bytes"]
        live.wait_for(lambda: active()["size_bytes"] > size, 30)  # a chunk was closed since
        live.wait_for(lambda: active()["duration_s"] > before["duration_s"] + 3 * FLUSH_INTERVAL_S, 30)  # ... and a flush began after `before`
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait(15)

    path = tmp_path / "recordings" / f"{recording_id}.mcap"
    counts, schemas, damage = _read_with_mcap(path)
    assert damage is not None, "a killed recording has no footer: the reader must meet the cut"
    for topic, count in before["topics"].items():
        if topic != "/events":  # events are written in the next tick's batch
            assert counts.get(topic, 0) >= count, (topic, counts, before["topics"])
    assert schemas["/joint_states"] == "foxglove.JointStates" and schemas["/camera/color/compressed"] == "foxglove.CompressedImage"

    (info,) = RecordingLibrary(tmp_path / "recordings").list()
    assert info["id"] == recording_id and info["truncated"] and not info["complete"] and "cut short" in info["stop_reason"]
    assert info["label"] == "killed" and info["topics"]["/joint_states"] >= before["topics"]["/joint_states"]
