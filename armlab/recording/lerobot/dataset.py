"""Recordings as one LeRobot dataset in LeRobot's v3.0 layout (codebase_version "v3.0", lerobot/datasets/utils.py and
lerobot_dataset.py), one episode per recording, all in chunk 0, file 0:

    meta/info.json                                     fps, features (dtype, shape, names), paths, totals
    meta/stats.json                                    per feature: min, max, mean, std, count, q01 q10 q50 q90 q99
    meta/tasks.parquet                                 task (the index) -> task_index
    meta/episodes/chunk-000/file-000.parquet           per episode: tasks, length, where its rows and video are, its stats
    data/chunk-000/file-000.parquet                    per frame: observation.state, action, timestamp, frame_index,
                                                       episode_index, index, task_index
    videos/observation.images.camera/chunk-000/file-000.mp4

The dataset is written to a folder next to `out` and renamed into place when complete: a failed export leaves nothing.
LeRobot's limits (data files up to 100 MB, video files up to 200 MB) are not enforced: one file each.
"""

from __future__ import annotations

import json
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from armlab.recording.lerobot import video
from armlab.recording.lerobot.episode import EpisodeFrames, ExportRefused, RecordedEpisode, read_episode, resample
from armlab.recording.library import RecordingBusy, RecordingLibrary

CODEBASE_VERSION = "v3.0"
CAMERA_KEY = "observation.images.camera"
CHUNKS_SIZE, DATA_FILES_SIZE_MB, VIDEO_FILES_SIZE_MB = 1000, 100, 200  # LeRobot's defaults (DEFAULT_CHUNK_SIZE, ...)
DATA_PATH = "data/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"  # DEFAULT_DATA_PATH
VIDEO_PATH = "videos/{video_key}/chunk-{chunk_index:03d}/file-{file_index:03d}.mp4"  # DEFAULT_VIDEO_PATH
EPISODES_PATH = "meta/episodes/chunk-{chunk_index:03d}/file-{file_index:03d}.parquet"  # DEFAULT_EPISODES_PATH
QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)  # LeRobot's DEFAULT_QUANTILES, as q01 ... q99
DEFAULT_FPS = 30
INDEX_FEATURES = ("timestamp", "frame_index", "episode_index", "index", "task_index")


@dataclass
class ExportResult:
    out: Path
    episodes: int
    frames: int
    fps: int
    tasks: list[str]
    seconds: float  # wall time of the export
    video_codec: str
    video_size_px: tuple[int, int]
    action_from_measured_frames: int

    def as_dict(self) -> dict:
        return {"out": str(self.out), "episodes": self.episodes, "frames": self.frames, "fps": self.fps, "tasks": self.tasks,
                "seconds": round(self.seconds, 3), "video_codec": self.video_codec, "video_size_px": list(self.video_size_px),
                "action_from_measured_frames": self.action_from_measured_frames}


def export_lerobot(recordings: list[str | Path], out: str | Path, *, fps: int = DEFAULT_FPS, tasks: list[str | None] | None = None,
                   allow_truncated: bool = False, codec: str | None = None) -> ExportResult:
    """Export MCAP recordings (one episode each, in this order) as a LeRobot v3.0 dataset in the new folder `out`
    (it must not exist, or be empty). tasks: per recording, its task (default: its label, else its jobs)."""
    started = time.perf_counter()
    if not recordings:
        raise ExportRefused("no recordings to export")
    out = Path(out)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise ExportRefused(f"{out} already exists and is not an empty folder: the export writes a new one")
    for module in ("pyarrow", "pandas", "av"):
        video.require(module)
    tasks = list(tasks or [None] * len(recordings))
    if len(tasks) != len(recordings):
        raise ExportRefused(f"{len(tasks)} tasks for {len(recordings)} recordings")
    episodes = [read_episode(path, task, allow_truncated) for path, task in zip(recordings, tasks)]
    frames = [resample(episode, fps) for episode in episodes]
    size = _video_size(episodes)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=out.parent))
    try:
        encoded = _write(staging, episodes, frames, fps, size, codec)
        if out.exists():
            out.rmdir()  # empty (checked above)
        staging.rename(out)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    task_names = list(dict.fromkeys(episode.task for episode in episodes))
    return ExportResult(out, len(episodes), sum(f.length for f in frames), fps, task_names, time.perf_counter() - started,
                        encoded.codec, (encoded.width, encoded.height), sum(f.action_from_measured_frames for f in frames))


def _video_size(episodes: list[RecordedEpisode]) -> tuple[int, int]:
    sizes = set()
    for episode in episodes:
        first = video.decode_jpeg(episode.camera_jpeg[0])
        sizes.add((first.shape[1], first.shape[0]))
    if len(sizes) != 1:
        raise ExportRefused(f"the recordings' cameras differ in size ({', '.join(f'{w}x{h}' for w, h in sorted(sizes))}): "
                            "export them as separate datasets")
    (width, height), = sizes
    width, height = video.even_size(width, height)
    if width < 2 or height < 2:
        raise ExportRefused(f"colour frames of {width}x{height} px are too small for a video")
    return width, height


def _write(root: Path, episodes: list[RecordedEpisode], frames: list[EpisodeFrames], fps: int, size: tuple[int, int],
           codec: str | None) -> video.EncodedVideo:
    task_names = list(dict.fromkeys(episode.task for episode in episodes))
    video_path = root / VIDEO_PATH.format(video_key=CAMERA_KEY, chunk_index=0, file_index=0)
    video_path.parent.mkdir(parents=True)
    encoded = video.encode(video_path, ((e.camera_jpeg, f.camera_index) for e, f in zip(episodes, frames)), fps, size, codec)
    columns = _data_columns(episodes, frames, fps, task_names)
    features = _features(episodes[0], encoded, video.video_info(video_path))
    _write_table(root / DATA_PATH.format(chunk_index=0, file_index=0), columns, features)

    episode_stats, starts = [], np.cumsum([0] + [f.length for f in frames])
    for number in range(len(episodes)):
        rows = slice(int(starts[number]), int(starts[number + 1]))
        stats = {key: feature_stats(columns[key][rows]) for key in columns}
        stats[CAMERA_KEY] = image_stats(encoded.episode_samples[number])
        episode_stats.append(stats)
    _write_episodes(root, episodes, frames, fps, starts, episode_stats)
    dataset_stats = {key: feature_stats(values) for key, values in columns.items()}
    dataset_stats[CAMERA_KEY] = image_stats(np.concatenate(encoded.episode_samples))
    _write_json(root / "meta/stats.json", dataset_stats)

    pandas = video.require("pandas")
    tasks_path = root / "meta/tasks.parquet"
    pandas.DataFrame({"task_index": range(len(task_names))}, index=task_names).to_parquet(tasks_path)  # as LeRobot's write_tasks

    total = int(starts[-1])
    _write_json(root / "meta/info.json", {
        "codebase_version": CODEBASE_VERSION, "robot_type": episodes[0].robot_type, "total_episodes": len(episodes),
        "total_frames": total, "total_tasks": len(task_names), "chunks_size": CHUNKS_SIZE, "data_files_size_in_mb": DATA_FILES_SIZE_MB,
        "video_files_size_in_mb": VIDEO_FILES_SIZE_MB, "fps": fps, "splits": {"train": f"0:{len(episodes)}"},
        "data_path": DATA_PATH, "video_path": VIDEO_PATH, "features": features,
    })
    return encoded


def _data_columns(episodes, frames, fps: int, task_names: list[str]) -> dict[str, np.ndarray]:
    """Every frame's row values, the episodes one after the other."""
    lengths = [f.length for f in frames]
    frame_index = np.concatenate([np.arange(n, dtype=np.int64) for n in lengths])
    return {
        "observation.state": np.concatenate([f.state for f in frames]),
        "action": np.concatenate([f.action for f in frames]),
        "timestamp": (frame_index / fps).astype(np.float32),
        "frame_index": frame_index,
        "episode_index": np.concatenate([np.full(n, number, np.int64) for number, n in enumerate(lengths)]),
        "index": np.arange(sum(lengths), dtype=np.int64),
        "task_index": np.concatenate([np.full(n, task_names.index(e.task), np.int64) for e, n in zip(episodes, lengths)]),
    }


def _features(episode: RecordedEpisode, encoded: video.EncodedVideo, info: dict) -> dict:
    joints = [f"{name}_rad" for name in episode.joint_names]
    dof = len(joints) + 1
    return {
        "observation.state": {"dtype": "float32", "shape": [dof], "names": [*joints, "gripper_width_m"]},
        "action": {"dtype": "float32", "shape": [dof], "names": [*joints, "gripper_grasp"]},
        CAMERA_KEY: {"dtype": "video", "shape": [encoded.height, encoded.width, 3], "names": ["height", "width", "channels"],
                     "info": info},
        "timestamp": {"dtype": "float32", "shape": [1], "names": None},
        "frame_index": {"dtype": "int64", "shape": [1], "names": None},
        "episode_index": {"dtype": "int64", "shape": [1], "names": None},
        "index": {"dtype": "int64", "shape": [1], "names": None},
        "task_index": {"dtype": "int64", "shape": [1], "names": None},
    }


def _write_table(path: Path, columns: dict[str, np.ndarray], features: dict) -> None:
    """The frames as Parquet: vectors as fixed-size lists (what LeRobot's datasets.Sequence(length=n) reads)."""
    pa = video.require("pyarrow")
    pq = video.require("pyarrow.parquet")
    arrays = {}
    for key, values in columns.items():
        dtype = pa.float32() if features[key]["dtype"] == "float32" else pa.int64()
        if values.ndim == 2:
            arrays[key] = pa.FixedSizeListArray.from_arrays(pa.array(values.ravel(), dtype), values.shape[1])
        else:
            arrays[key] = pa.array(values, dtype)
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.table(arrays), path, compression="snappy")


def _write_episodes(root: Path, episodes, frames, fps: int, starts: np.ndarray, episode_stats: list[dict]) -> None:
    pa = video.require("pyarrow")
    pq = video.require("pyarrow.parquet")
    rows: dict[str, list] = {}
    for number, (episode, episode_frames) in enumerate(zip(episodes, frames)):
        row = {
            "episode_index": number, "tasks": [episode.task], "length": episode_frames.length,
            "data/chunk_index": 0, "data/file_index": 0,
            "dataset_from_index": int(starts[number]), "dataset_to_index": int(starts[number + 1]),
            f"videos/{CAMERA_KEY}/chunk_index": 0, f"videos/{CAMERA_KEY}/file_index": 0,
            f"videos/{CAMERA_KEY}/from_timestamp": float(starts[number]) / fps,
            f"videos/{CAMERA_KEY}/to_timestamp": float(starts[number + 1]) / fps,
            "meta/episodes/chunk_index": 0, "meta/episodes/file_index": 0,
            **{f"stats/{key}/{name}": value for key, stats in episode_stats[number].items() for name, value in stats.items()},
        }
        for key, value in row.items():
            rows.setdefault(key, []).append(value)
    path = root / EPISODES_PATH.format(chunk_index=0, file_index=0)
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pydict(rows), path, compression="snappy")


def _write_json(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=4, ensure_ascii=False) + "\n")


def _stats(values: np.ndarray, axis) -> dict[str, np.ndarray]:
    stats = {"min": values.min(axis=axis), "max": values.max(axis=axis), "mean": values.mean(axis=axis),
             "std": values.std(axis=axis)}
    for q in QUANTILES:
        stats[f"q{round(q * 100):02d}"] = np.quantile(values, q, axis=axis)
    return stats


def feature_stats(values: np.ndarray) -> dict[str, list]:
    """A numeric feature's statistics as LeRobot stores them: per dimension (a scalar as a list of one)."""
    values = np.asarray(values, dtype=np.float64).reshape(len(values), -1)
    stats = {name: np.atleast_1d(value).tolist() for name, value in _stats(values, 0).items()}
    return {**stats, "count": [len(values)]}


def image_stats(samples: np.ndarray) -> dict[str, list]:
    """Per colour channel over sampled frames (S, 3, h, w) in [0, 1]: shape (3, 1, 1) each, count: frames sampled."""
    channels = samples.transpose(1, 0, 2, 3).reshape(3, -1)
    stats = {name: np.asarray(value).reshape(3, 1, 1).tolist() for name, value in _stats(channels, 1).items()}
    return {**stats, "count": [int(len(samples))]}


def export_library_recordings(library: RecordingLibrary, recording_ids: list[str], out: str | Path, **options) -> ExportResult:
    """Export recordings of a RecordingLibrary by id: NotFound for an unknown id, RecordingBusy for the running one."""
    paths = [library.path(recording_id) for recording_id in recording_ids]
    active = library.active()
    if active is not None and active["id"] in recording_ids:
        raise RecordingBusy(f"recording {active['id']} is still being written: stop it first")
    return export_lerobot(paths, out, **options)


__all__ = ["CAMERA_KEY", "CODEBASE_VERSION", "ExportResult", "export_lerobot", "export_library_recordings", "feature_stats",
           "image_stats", "read_episode", "resample"]
