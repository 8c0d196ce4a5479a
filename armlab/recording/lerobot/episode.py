"""One recording as a LeRobot episode: its channels read back (reader.py) and resampled to a fixed frame rate.

Times are each reading's own stamp (nanoseconds since the Unix epoch, time.time() on every device): the measured
joints' reading time, the colour frame's capture time, the commanded reference's and the gripper's sample time.
Frame k of an episode is at t0 + k / fps, where t0 is the first time every channel has a value (joints, gripper,
camera) and the last frame is at or before the end of the shortest channel. Each channel is taken as it was last
known at the frame time (the newest sample at or before it: causal, as a policy would have seen it, and every
value is one the station recorded, never an interpolation):

- observation.state: the measured joints (rad) and the gripper's measured width (m);
- action: the commanded joints (rad) and the gripper's command (1 grasp, 0 release). Where no command was sent
  (a teach session moved by hand, after a halt: no /joint_commands for more than STALE_COMMAND_NS; the sampler
  repeats a held command every HELD_COMMAND_PERIOD_NS), the joints' action is the measured joints at the next
  frame, where the arm went (counted in `action_from_measured_frames`);
- the camera: the newest colour frame captured at or before the frame time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from armlab.errors import InvalidInput
from armlab.recording.reader import iter_messages, summarize
from armlab.recording.sampler import HELD_COMMAND_PERIOD_NS

JOINTS, COMMANDS, GRIPPER, COLOR = "/joint_states", "/joint_commands", "/gripper", "/camera/color/compressed"
STALE_COMMAND_NS = HELD_COMMAND_PERIOD_NS * 3 // 2  # a command this old was not held any more (halted, limp)
NS_PER_S = 1_000_000_000


class ExportRefused(InvalidInput):
    """A recording that cannot be exported as it is (empty, no camera, cut short, ...); the message says why."""


@dataclass
class RecordedEpisode:
    """One recording's channels as arrays (times: int64 ns since the epoch, sorted)."""

    recording_id: str
    task: str
    robot_type: str
    truncated: bool
    joint_names: list[str]
    joint_ns: np.ndarray  # (n,)
    joint_rad: np.ndarray  # (n, dof)
    command_ns: np.ndarray  # (m,)
    command_rad: np.ndarray  # (m, dof), in joint_names' order
    gripper_ns: np.ndarray  # (g,)
    gripper_width_m: np.ndarray  # (g,)
    gripper_grasp: np.ndarray  # (g,) 1.0 while the last command was 'grasp', else 0.0
    camera_ns: np.ndarray  # (c,)
    camera_jpeg: list[bytes] = field(repr=False)


@dataclass
class EpisodeFrames:
    """An episode resampled at `fps`: K frames."""

    fps: int
    time_ns: np.ndarray  # (K,) the frame times
    state: np.ndarray  # (K, dof + 1) float32: joints (rad), gripper width (m)
    action: np.ndarray  # (K, dof + 1) float32: commanded joints (rad), gripper grasp (1) / release (0)
    camera_index: np.ndarray  # (K,) the colour frame (index into RecordedEpisode.camera_jpeg) shown at each frame
    joint_index: np.ndarray  # (K,) the measured joint state (index into RecordedEpisode.joint_ns) in `state`
    action_from_measured_frames: int

    @property
    def length(self) -> int:
        return int(len(self.time_ns))


def _stamp_ns(message) -> int:
    return int(message.timestamp.seconds) * NS_PER_S + int(message.timestamp.nanos)


def _sorted(times: list[int], *columns):
    order = np.argsort(np.asarray(times, dtype=np.int64), kind="stable")
    return (np.asarray(times, dtype=np.int64)[order], *[column[order] if isinstance(column, np.ndarray) else [column[i] for i in order]
                                                       for column in columns])


def _sidecar_task(path: Path) -> str:
    """What the recording was (its label, else the jobs that ran, else the station states) from its sidecar."""
    try:
        info = json.loads(path.with_suffix(".json").read_text())
    except (OSError, ValueError):
        return ""
    if info.get("label"):
        return str(info["label"])
    if info.get("jobs"):
        return "armlab: " + ", ".join(str(job) for job in info["jobs"])
    states = [str(state) for state in info.get("states") or [] if state != "idle"]
    return "armlab: " + ", ".join(states) if states else ""


def read_episode(path: str | Path, task: str | None = None, allow_truncated: bool = False) -> RecordedEpisode:
    """Read the channels an export needs. ExportRefused: cut short (unless allow_truncated: what is readable, up to
    the last complete chunk), no joint states, no gripper, no colour frames; DamagedRecording: not an MCAP file."""
    path = Path(path)
    if not path.is_file():
        raise ExportRefused(f"no recording file {path}")
    summary = summarize(path)  # DamagedRecording for a file that is not MCAP
    name = path.stem
    if not summary.complete and not allow_truncated:
        raise ExportRefused(f"recording {name} was cut short (the station stopped while recording, or it is still being "
                            "written): its end is missing; export it with allow_truncated (--allow-truncated) to take "
                            "what is readable, up to its last complete chunk")
    counts = {topic: data["count"] for topic, data in summary.topics.items()}
    if summary.message_count == 0:
        raise ExportRefused(f"recording {name} is empty: it holds no messages")
    if not counts.get(JOINTS):
        raise ExportRefused(f"recording {name} has no measured joints ({JOINTS}): nothing to export "
                            "(recorded on a station without an arm?)")
    if not counts.get(COLOR):
        raise ExportRefused(f"recording {name} has no colour camera frames ({COLOR}): a LeRobot dataset needs the camera "
                            "(recorded with recording.camera_rate_hz 0, or the camera was off)")
    if not counts.get(GRIPPER):
        raise ExportRefused(f"recording {name} has no gripper readings ({GRIPPER}): observation.state needs its width")

    names: list[str] | None = None
    joint_ns, joint_rad, command_ns, command_rad = [], [], [], []
    gripper_ns, width_m, grasp = [], [], []
    camera_ns, jpegs = [], []
    for topic, _, _, message in iter_messages(path, {JOINTS, COMMANDS, GRIPPER, COLOR}):
        if topic == JOINTS:
            if names is None:
                names = [joint.name for joint in message.joints]
            if [joint.name for joint in message.joints] != names:
                raise ExportRefused(f"recording {name}: the joints changed within it ({names} then "
                                    f"{[joint.name for joint in message.joints]})")
            joint_ns.append(_stamp_ns(message))
            joint_rad.append([joint.position for joint in message.joints])
        elif topic == COMMANDS:
            by_name = {joint.name: joint.position for joint in message.joints}
            command_ns.append(_stamp_ns(message))
            command_rad.append(by_name)
        elif topic == GRIPPER:
            gripper_ns.append(int(round(float(message["time_s"]) * NS_PER_S)))
            width_m.append(float(message["width_m"]))
            grasp.append(1.0 if message.get("command") == "grasp" else 0.0)
        else:
            if message.format.lower() not in ("jpeg", "jpg", "png"):
                raise ExportRefused(f"recording {name}: a colour frame in format '{message.format}' (expected jpeg)")
            camera_ns.append(_stamp_ns(message))
            jpegs.append(bytes(message.data))
    if not joint_ns or not camera_ns or not gripper_ns:  # a truncated file whose readable part lacks a channel
        missing = [topic for topic, values in ((JOINTS, joint_ns), (COLOR, camera_ns), (GRIPPER, gripper_ns)) if not values]
        raise ExportRefused(f"recording {name}: its readable part has no {', '.join(missing)}")
    assert names is not None
    dof = len(names)
    commands = np.empty((len(command_rad), dof))
    for row, by_name in enumerate(command_rad):
        if set(names) - set(by_name):
            raise ExportRefused(f"recording {name}: a commanded reference without joint(s) {sorted(set(names) - set(by_name))}")
        commands[row] = [by_name[joint] for joint in names]
    meta = summary.metadata.get("armlab", {})
    task = (task or "").strip() or meta.get("label", "") or _sidecar_task(path) or "armlab recording"
    robot_type = meta.get("workcell", "") or "armlab"
    joint_ns_a, joint_rad_a = _sorted(joint_ns, np.asarray(joint_rad, dtype=float).reshape(-1, dof))
    command_ns_a, command_rad_a = _sorted(command_ns, commands)
    gripper_ns_a, width_a, grasp_a = _sorted(gripper_ns, np.asarray(width_m), np.asarray(grasp))
    camera_ns_a, jpegs_sorted = _sorted(camera_ns, jpegs)
    return RecordedEpisode(name, task, robot_type, not summary.complete, names, joint_ns_a, joint_rad_a, command_ns_a, command_rad_a,
                           gripper_ns_a, width_a, grasp_a, camera_ns_a, jpegs_sorted)


def _held(times_ns: np.ndarray, at_ns: np.ndarray) -> np.ndarray:
    """Per time in at_ns: the index of the newest sample at or before it (-1: none yet)."""
    return np.searchsorted(times_ns, at_ns, side="right") - 1


def resample(episode: RecordedEpisode, fps: int) -> EpisodeFrames:
    """The episode at `fps` frames per second (module docstring); ExportRefused if its channels never overlap."""
    if not isinstance(fps, int) or not 1 <= fps <= 240:
        raise ExportRefused(f"fps must be a whole number from 1 to 240 (got {fps})")
    start_ns = max(int(episode.joint_ns[0]), int(episode.camera_ns[0]), int(episode.gripper_ns[0]))
    end_ns = min(int(episode.joint_ns[-1]), int(episode.camera_ns[-1]), int(episode.gripper_ns[-1]))
    if end_ns < start_ns:
        raise ExportRefused(f"recording {episode.recording_id}: its joints, gripper and camera frames never overlap in time "
                            "(one channel ended before another began)")
    count = (end_ns - start_ns) * fps // NS_PER_S + 1
    time_ns = start_ns + (np.arange(count, dtype=np.int64) * NS_PER_S) // fps
    joint_index = _held(episode.joint_ns, time_ns)
    gripper_index = _held(episode.gripper_ns, time_ns)
    camera_index = _held(episode.camera_ns, time_ns)
    measured = episode.joint_rad[joint_index]
    state = np.column_stack([measured, episode.gripper_width_m[gripper_index]]).astype(np.float32)
    next_measured = measured[np.minimum(np.arange(count) + 1, count - 1)]
    commanded = next_measured.copy()
    if len(episode.command_ns):
        command_index = _held(episode.command_ns, time_ns)
        fresh = (command_index >= 0) & (time_ns - episode.command_ns[np.maximum(command_index, 0)] <= STALE_COMMAND_NS)
        commanded[fresh] = episode.command_rad[command_index[fresh]]
        from_measured = int(count - np.count_nonzero(fresh))
    else:
        from_measured = int(count)
    action = np.column_stack([commanded, episode.gripper_grasp[gripper_index]]).astype(np.float32)
    return EpisodeFrames(fps, time_ns, state, action, camera_index, joint_index, from_measured)
