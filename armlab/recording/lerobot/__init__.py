"""Recordings exported as LeRobot datasets (issue 23 item 3): LeRobot's v3.0 layout, which LeRobot's own
`LeRobotDataset(repo_id, root=DIR)` loads. episode.py: a recording read back and resampled to a fixed fps;
video.py: the camera as an MP4 (PyAV, AV1 as LeRobot encodes); dataset.py: the files. Needs the `lerobot` extra
(pyarrow, pandas, av: imported when an export runs, so the station runs without them); LeRobot itself is not needed.
"""

from armlab.recording.lerobot.dataset import (
           CAMERA_KEY,
           CODEBASE_VERSION,
           ExportResult,
           export_lerobot,
           export_library_recordings,
)
from armlab.recording.lerobot.episode import EpisodeFrames, ExportRefused, RecordedEpisode, read_episode, resample
from armlab.recording.lerobot.video import ExtraMissing

__all__ = ["CAMERA_KEY", "CODEBASE_VERSION", "EpisodeFrames", "ExportRefused", "ExportResult", "ExtraMissing", "RecordedEpisode",
           "export_lerobot", "export_library_recordings", "read_episode", "resample"]
