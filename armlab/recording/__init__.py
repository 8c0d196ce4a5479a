"""Recording the station to MCAP files in Foxglove's schemas (issue 23 item 2).

channels.py: the topics and their messages (StationChannels.open(context) for any foxglove-sdk sink, e.g. a live
WebSocket server; StationChannels.on_file(McapFile) for a recording); sampler.py: the threads that sample the station
into them; mcap_file.py: the MCAP file (the mcap library, the GIL released while compressing and writing);
recorder.py: one recording; library.py: the recordings folder (start/stop one at a time, list, delete, the disk
budget); reader.py: reading them back, files cut short included; lerobot/: recordings exported as LeRobot v3.0
datasets (issue 23 item 3; the `lerobot` extra, imported only by its callers).
"""

from armlab.recording.channels import TOPICS, StationChannels
from armlab.recording.library import AlreadyRecording, DiskFull, NotRecording, RecordingBusy, RecordingLibrary
from armlab.recording.reader import DamagedRecording, RecordingSummary, iter_messages, summarize
from armlab.recording.recorder import Recording

__all__ = [
    "TOPICS", "AlreadyRecording", "DamagedRecording", "DiskFull", "NotRecording", "Recording", "RecordingBusy",
    "RecordingLibrary", "RecordingSummary", "StationChannels", "iter_messages", "summarize",
]
