"""Recordings exported as LeRobot v3.0 datasets (issue 23 item 3), checked against LeRobot's published layout
(lerobot/datasets/utils.py: INFO_PATH, DEFAULT_DATA_PATH, DEFAULT_VIDEO_PATH, DEFAULT_EPISODES_PATH, DEFAULT_TASKS_PATH,
DEFAULT_FEATURES; lerobot_dataset.py: the episodes' columns) with pyarrow, pandas and PyAV (LeRobot itself needs torch:
its LeRobotDataset load check runs in bench/lerobot_load_check.py). The rows are the recording's own values: the
measured joints and gripper width newest at or before each frame time, found here by a plain scan of the MCAP; the
video has one frame per row, of the camera's size, each the colour frame captured at or before its time. Bad input
(cut short, empty, no camera, not MCAP, a used folder) is refused with the reason and writes nothing."""

from __future__ import annotations

import json
import os
import threading
import time

import av
import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from armlab.cli import main as cli_main
from armlab.recording import DamagedRecording, RecordingLibrary, iter_messages
from armlab.recording.lerobot import CAMERA_KEY, ExportRefused, export_lerobot, export_library_recordings
from armlab.recording.lerobot.fair_threads import realtime_thread_ids
from armlab.station.config import RecordingConfig
from lerobot_helpers import (
    NAMES,
    RECORDING_ID,
    START_NS,
    SineArmStation,
    command_at,
    level,
    newest_at_or_before,
    write_recording,
)

FPS = 30
DATA = "data/chunk-000/file-000.parquet"
EPISODES = "meta/episodes/chunk-000/file-000.parquet"
VIDEO = f"videos/{CAMERA_KEY}/chunk-000/file-000.mp4"
# The policy as this module was collected, before any export ran (the `exported` fixture's export runs first).
STARTED_FAIRLY = not hasattr(os, "sched_getscheduler") or os.sched_getscheduler(0) == os.SCHED_OTHER
STAT_NAMES = {"min", "max", "mean", "std", "count", "q01", "q10", "q50", "q90", "q99"}


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """One 3 s recording (camera 15 fps, commands for its first second) exported at 30 fps."""
    root = tmp_path_factory.mktemp("lerobot")
    path = write_recording(root / f"{RECORDING_ID}.mcap")
    result = export_lerobot([path], root / "dataset", fps=FPS)
    return path, root / "dataset", result


def wait_for(predicate, timeout_s: float = 60.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.01)


def recorded(path, topic):
    return list(iter_messages(path, {topic}))


def stamp(message) -> int:
    return message.timestamp.seconds * 10**9 + message.timestamp.nanos


def test_the_files_are_lerobots_v3_layout(exported):
    _, out, result = exported
    files = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert files == sorted([DATA, EPISODES, VIDEO, "meta/info.json", "meta/stats.json", "meta/tasks.parquet"])
    info = json.loads((out / "meta/info.json").read_text())
    assert info["codebase_version"] == "v3.0" and info["fps"] == FPS and info["robot_type"] == "rx200_armlab"
    assert info["data_path"] == "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"
    assert info["video_path"] == "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"
    assert (info["total_episodes"], info["total_frames"], info["total_tasks"]) == (1, result.frames, 1)
    assert info["chunks_size"] == 1000 and info["splits"] == {"train": "0:1"}
    features = info["features"]
    joints = [f"{name}_rad" for name in NAMES]
    assert features["observation.state"] == {"dtype": "float32", "shape": [6], "names": [*joints, "gripper_width_m"]}
    assert features["action"] == {"dtype": "float32", "shape": [6], "names": [*joints, "gripper_grasp"]}
    for key, dtype in (("timestamp", "float32"), ("frame_index", "int64"), ("episode_index", "int64"), ("index", "int64"),
                       ("task_index", "int64")):
        assert features[key] == {"dtype": dtype, "shape": [1], "names": None}
    camera = features[CAMERA_KEY]
    assert camera["dtype"] == "video" and camera["shape"] == [48, 64, 3] and camera["names"] == ["height", "width", "channels"]
    assert camera["info"]["video.codec"] == "av1" and camera["info"]["video.pix_fmt"] == "yuv420p" and camera["info"]["video.fps"] == FPS

    data = pq.read_table(out / DATA)
    assert data.schema.field("observation.state").type == pa.list_(pa.float32(), 6)  # datasets.Sequence(length=6)
    assert data.schema.field("action").type == pa.list_(pa.float32(), 6)
    assert data.schema.field("timestamp").type == pa.float32()
    assert all(data.schema.field(key).type == pa.int64() for key in ("frame_index", "episode_index", "index", "task_index"))
    assert set(data.column_names) == set(features) - {CAMERA_KEY} and data.num_rows == result.frames

    episodes = pq.read_table(out / EPISODES).to_pylist()
    (episode,) = episodes
    assert episode["episode_index"] == 0 and episode["tasks"] == ["stack three"] and episode["length"] == result.frames
    assert (episode["dataset_from_index"], episode["dataset_to_index"]) == (0, result.frames)
    assert (episode["data/chunk_index"], episode["data/file_index"], episode["meta/episodes/chunk_index"]) == (0, 0, 0)
    assert episode[f"videos/{CAMERA_KEY}/chunk_index"] == 0 and episode[f"videos/{CAMERA_KEY}/from_timestamp"] == 0.0
    assert episode[f"videos/{CAMERA_KEY}/to_timestamp"] == pytest.approx(result.frames / FPS)
    assert {name.rsplit("/", 1)[1] for name in episode if name.startswith("stats/observation.state/")} == STAT_NAMES

    tasks = pd.read_parquet(out / "meta/tasks.parquet")  # as LeRobot's load_tasks: the task is the index
    assert list(tasks.index) == ["stack three"] and tasks.loc["stack three"].task_index == 0

    stats = json.loads((out / "meta/stats.json").read_text())
    assert set(stats) == set(features)
    assert all(set(stats[key]) == STAT_NAMES for key in stats)
    assert np.asarray(stats["observation.state"]["mean"]).shape == (6,) and stats["observation.state"]["count"] == [result.frames]
    assert np.asarray(stats[CAMERA_KEY]["mean"]).shape == (3, 1, 1) and 0.0 <= stats[CAMERA_KEY]["min"][0][0][0] <= 1.0


def expected_rows(path, frames: int, fps: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The recording's own values at the frame times t0 + k / fps (t0: every channel has one), by plain scans of the
    MCAP: state (measured joints, gripper width) and action (the command held within 1.5 s, else the measured joints
    at the next frame; the gripper's command), float32; and how many frames had a held command."""
    joints = recorded(path, "/joint_states")
    grippers = recorded(path, "/gripper")
    colours = recorded(path, "/camera/color/compressed")
    commands = recorded(path, "/joint_commands")
    joint_ns = [stamp(m) for _, _, _, m in joints]
    gripper_ns = [round(m["time_s"] * 1e9) for _, _, _, m in grippers]
    command_ns = [stamp(m) for _, _, _, m in commands]
    t0 = max(joint_ns[0], gripper_ns[0], stamp(colours[0][3]))
    states, actions, by_command = [], [], 0
    for k in range(frames):
        t_ns = t0 + k * 10**9 // fps
        q = [joint.position for joint in joints[newest_at_or_before(joint_ns, t_ns)][3].joints]
        gripper = grippers[newest_at_or_before(gripper_ns, t_ns)][3]
        states.append([*q, gripper["width_m"]])
        c = newest_at_or_before(command_ns, t_ns)
        if c >= 0 and t_ns - command_ns[c] <= 1_500_000_000:  # a command held within the last 1.5 s
            commanded = [joint.position for joint in commands[c][3].joints]
            by_command += 1
        else:  # none (moved by hand): where the arm went, the measured joints at the next frame
            next_ns = t0 + min(k + 1, frames - 1) * 10**9 // fps
            commanded = [joint.position for joint in joints[newest_at_or_before(joint_ns, next_ns)][3].joints]
        actions.append([*commanded, 1.0 if gripper["command"] == "grasp" else 0.0])
    return np.float32(states), np.float32(actions), by_command


def test_the_rows_are_the_recorded_joints_and_gripper_at_the_frame_times(exported):
    path, out, result = exported
    data = pq.read_table(out / DATA).to_pydict()
    assert data["frame_index"] == list(range(result.frames)) and data["index"] == list(range(result.frames))
    assert set(data["episode_index"]) == {0} and set(data["task_index"]) == {0}
    assert np.array_equal(np.asarray(data["timestamp"], np.float32), (np.arange(result.frames) / FPS).astype(np.float32))
    states, actions = np.asarray(data["observation.state"]), np.asarray(data["action"])
    expected_states, expected_actions, by_command = expected_rows(path, result.frames, FPS)
    assert np.array_equal(states, expected_states)  # exactly the recorded float32 values, frame by frame
    assert np.array_equal(actions, expected_actions)
    assert 0 < by_command < result.frames and result.action_from_measured_frames == result.frames - by_command
    assert actions[0, :5].tolist() == np.float32(command_at(0.05)).tolist()  # the first frame: the camera's first, at 0.05 s
    held = [k for k in range(result.frames) if 1.0 < 0.05 + k / FPS < 2.49]  # commands end at 0.99 s: held 1.5 s more
    assert held and all(actions[k, :5].tolist() == np.float32(command_at(0.99)).tolist() for k in held)
    assert states[:, 5].min() < states[:, 5].max() and set(actions[:, 5]) == {0.0, 1.0}  # the gripper closes in it


def test_a_recording_made_by_the_recorder_exports_its_own_readings(tmp_path):
    """The recorder's own sampler (joints and commands at 100 Hz, gripper at 30 Hz, the camera) on a stand-in station
    with the RX200's model: every row is the recorded reading at its time, every action the recorded command."""
    library = RecordingLibrary(tmp_path / "recordings", RecordingConfig(flush_interval_s=0.05, min_free_mb=0.0, depth_rate_hz=0.0))
    with SineArmStation() as station:
        library.start(station, label="sine")
        wait_for(lambda: library.active()["topics"].get("/camera/color/compressed", 0) >= 30
                 and library.active()["topics"].get("/joint_states", 0) >= 100)
        info = library.stop()
    result = export_library_recordings(library, [info["id"]], tmp_path / "dataset", fps=10)
    data = pq.read_table(tmp_path / "dataset" / DATA).to_pydict()
    states, actions, by_command = expected_rows(library.path(info["id"]), result.frames, 10)
    assert result.frames >= 5 and result.tasks == ["sine"]
    assert np.array_equal(np.asarray(data["observation.state"]), states)
    assert np.array_equal(np.asarray(data["action"]), actions) and by_command == result.frames  # commanded throughout
    with av.open(str(tmp_path / "dataset" / VIDEO)) as container:
        assert [(f.width, f.height) for f in container.decode(video=0)] == [(32, 24)] * result.frames  # camera_scale 0.5


def test_the_video_has_a_frame_per_row_each_the_colour_frame_shown_then(exported):
    path, out, result = exported
    colours = [stamp(m) for _, _, _, m in recorded(path, "/camera/color/compressed")]
    joints = [stamp(m) for _, _, _, m in recorded(path, "/joint_states")]
    t0 = max(joints[0], colours[0], START_NS)
    with av.open(str(out / VIDEO)) as container:
        stream = container.streams.video[0]
        assert stream.codec_context.name in ("libdav1d", "av1") and (stream.width, stream.height) == (64, 48)
        decoded = [(float(frame.time), frame.to_ndarray(format="rgb24")) for frame in container.decode(stream)]
    assert len(decoded) == result.frames
    for k, (time_s, rgb) in enumerate(decoded):
        assert time_s == pytest.approx(k / FPS, abs=1e-4)  # LeRobot's tolerance_s: frame k at k / fps
        shown = newest_at_or_before(colours, t0 + k * 10**9 // FPS)
        assert abs(float(rgb.mean()) - level(shown)) < 3, f"frame {k} shows colour frame {shown}?"  # neighbours are 8 apart


def test_recordings_are_episodes_one_after_the_other(tmp_path):
    first = write_recording(tmp_path / "20270115T080000Z-000001.mcap", 2.0, label="pick")
    second = write_recording(tmp_path / "20270115T080100Z-000002.mcap", 1.5, label="place", camera_hz=30.0)
    third = write_recording(tmp_path / "20270115T080200Z-000003.mcap", 1.0, label="pick")
    result = export_lerobot([first, second, third], tmp_path / "out", fps=10)
    episodes = pq.read_table(tmp_path / "out" / EPISODES).to_pylist()
    lengths = [episode["length"] for episode in episodes]
    assert [episode["tasks"] for episode in episodes] == [["pick"], ["place"], ["pick"]] and sum(lengths) == result.frames
    bounds = np.cumsum([0, *lengths])
    for number, episode in enumerate(episodes):
        assert (episode["dataset_from_index"], episode["dataset_to_index"]) == (bounds[number], bounds[number + 1])
        assert episode[f"videos/{CAMERA_KEY}/from_timestamp"] == pytest.approx(bounds[number] / 10)
    data = pq.read_table(tmp_path / "out" / DATA).to_pydict()
    assert data["episode_index"] == [n for n, length in enumerate(lengths) for _ in range(length)]
    assert data["frame_index"] == [k for length in lengths for k in range(length)]
    assert data["task_index"] == [[0, 1, 0][n] for n, length in enumerate(lengths) for _ in range(length)]
    assert list(pd.read_parquet(tmp_path / "out/meta/tasks.parquet").index) == ["pick", "place"]
    with av.open(str(tmp_path / "out" / VIDEO)) as container:
        assert sum(1 for _ in container.decode(video=0)) == result.frames


def _cut(path, folder, fraction: float):
    data = path.read_bytes()
    cut = folder / "20270115T090000Z-c0ffee.mcap"
    cut.write_bytes(data[: int(len(data) * fraction)])
    return cut


def test_a_cut_short_recording_is_refused_unless_asked_then_exported_to_its_last_chunk(exported, tmp_path):
    path, _, whole = exported
    cut = _cut(path, tmp_path, 0.6)
    with pytest.raises(ExportRefused, match="cut short"):
        export_lerobot([cut], tmp_path / "refused")
    assert not (tmp_path / "refused").exists() and [p.name for p in tmp_path.iterdir()] == [cut.name]  # nothing written
    result = export_lerobot([cut], tmp_path / "partial", allow_truncated=True)
    assert 0 < result.frames < whole.frames
    assert pq.read_table(tmp_path / "partial" / DATA).num_rows == result.frames


def test_bad_recordings_are_refused_with_the_reason(tmp_path):
    from armlab.recording.mcap_file import McapFile

    empty = tmp_path / "20270115T080000Z-000000.mcap"
    McapFile(empty, 16 * 1024).close()
    with pytest.raises(ExportRefused, match="empty"):
        export_lerobot([empty], tmp_path / "a")
    blind = write_recording(tmp_path / "20270115T080000Z-000001.mcap", 1.0, camera=False)
    with pytest.raises(ExportRefused, match="no colour camera frames"):
        export_lerobot([blind], tmp_path / "b")
    junk = tmp_path / "20270115T080000Z-000002.mcap"
    junk.write_bytes(b"not a recording at all" * 10)
    with pytest.raises(DamagedRecording, match="not an MCAP"):
        export_lerobot([junk], tmp_path / "c")
    good = write_recording(tmp_path / "20270115T080000Z-000003.mcap", 1.0)
    (tmp_path / "used").mkdir()
    (tmp_path / "used" / "keep.txt").write_text("mine")
    with pytest.raises(ExportRefused, match="not an empty folder"):
        export_lerobot([good], tmp_path / "used")
    assert [p.name for p in (tmp_path / "used").iterdir()] == ["keep.txt"]
    with pytest.raises(ExportRefused, match="fps"):
        export_lerobot([good], tmp_path / "d", fps=0)
    assert sorted(p.name for p in tmp_path.iterdir() if not p.suffix) == ["used"]  # no dataset, no staging folder left


def test_the_cli_exports_by_id_and_refuses_with_one_line(tmp_path, capsys):
    library = tmp_path / "recordings"
    library.mkdir()
    write_recording(library / f"{RECORDING_ID}.mcap", 1.0)
    code = cli_main(["recordings", "export", RECORDING_ID, "--format", "lerobot", "--out", str(tmp_path / "ds"),
                     "--recordings", str(library), "--fps", "15", "--task", "demo", "--json"])
    assert code == 0
    result = json.loads(capsys.readouterr().out)
    assert result["fps"] == 15 and result["tasks"] == ["demo"] and result["episodes"] == 1
    assert json.loads((tmp_path / "ds/meta/info.json").read_text())["total_frames"] == result["frames"]
    assert cli_main(["recordings", "list", "--recordings", str(library), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)[0]["id"] == RECORDING_ID
    code = cli_main(["recordings", "export", "20270115T080000Z-ffffff", "--format", "lerobot", "--out", str(tmp_path / "x"),
                     "--recordings", str(library)])
    assert code == 1 and "no recording '20270115T080000Z-ffffff'" in capsys.readouterr().err


def test_the_rest_route_sends_the_dataset_as_a_zip(tmp_path):
    import io
    import zipfile

    from fastapi.testclient import TestClient

    from server.app import create_app

    write_recording(tmp_path / f"{RECORDING_ID}.mcap", 1.0)
    write_recording(tmp_path / "20270115T080000Z-000001.mcap", 1.0, camera=False)
    app = create_app(station_factory=lambda: None, token="t", allowed_hosts=("testserver",))
    app.state.recordings = RecordingLibrary(tmp_path)  # no lifespan: no station, only the library
    client = TestClient(app)
    response = client.get(f"/api/recordings/{RECORDING_ID}/export", params={"format": "lerobot", "fps": 10, "task": "demo"})
    assert response.status_code == 200, response.text
    assert response.headers["content-type"] == "application/zip"
    with zipfile.ZipFile(io.BytesIO(response.content)) as zipped:
        names = set(zipped.namelist())
        info = json.loads(zipped.read(f"{RECORDING_ID}-lerobot/meta/info.json"))
    assert {f"{RECORDING_ID}-lerobot/{name}" for name in (DATA, EPISODES, VIDEO, "meta/tasks.parquet", "meta/stats.json")} <= names
    assert info["fps"] == 10 and info["codebase_version"] == "v3.0"
    refused = client.get("/api/recordings/20270115T080000Z-000001/export")
    assert refused.status_code == 422 and "no colour camera frames" in refused.json()["error"]["message"]
    assert client.get("/api/recordings/20270115T080000Z-ffffff/export").status_code == 404
    assert client.get(f"/api/recordings/{RECORDING_ID}/export", params={"format": "csv"}).status_code == 422


@pytest.mark.skipif(not hasattr(os, "sched_getscheduler") or os.geteuid() != 0,
                    reason="an encoder can raise a thread to real-time scheduling only with root's CAP_SYS_NICE")
def test_encoding_leaves_no_thread_in_real_time_scheduling(tmp_path):
    """SVT-AV1 run as root put the exporting thread and its ~40 workers into SCHED_FIFO 99, and everything they
    started later inherited it: the suite's worker took its Playwright driver and Chromium down with it and starved
    the machine (a CI run did not finish in 90 minutes). After an export no thread of the process is real-time, and a
    thread started afterwards is not either."""
    if not STARTED_FAIRLY:
        pytest.skip("the suite was started in real-time or other scheduling: a change by the export cannot be told apart")
    path = write_recording(tmp_path / f"{RECORDING_ID}.mcap")
    export_lerobot([path], tmp_path / "dataset", fps=FPS)
    assert os.sched_getscheduler(0) == os.SCHED_OTHER
    assert realtime_thread_ids() == set()
    policy = []
    later = threading.Thread(target=lambda: policy.append(os.sched_getscheduler(0)))
    later.start()
    later.join()
    assert policy == [os.SCHED_OTHER]
