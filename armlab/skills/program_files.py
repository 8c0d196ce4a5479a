"""Program files of every format, for `armlab programs` and the REST upload and download: import a ROS 2 bag of
joint states, the course's joint text (jointdata), or the station's own CSV and JSON as a new program; export a
program as a ROS 2 bag (MCAP or sqlite3), CSV or JSON; a repeat's cycle trace as a bag.

An import is read and converted (armlab.program_formats: names matched to the arm's joints, every sample inside
the joint limits, or clamped by at most the caller's clamp_rad), every waypoint then passes the station's pose
check (limits, the table, the workspace box, the fingers and the arm's own body) and only then is the program
saved, in one transaction: a refused file stores nothing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from armlab import program_formats, program_io
from armlab.errors import InvalidInput
from armlab.program_formats import ImportOptions
from armlab.skills.programs import export_program, get_program, import_program, move_times_s
from armlab.skills.repeat_plan import check_waypoints
from armlab.station.core import Station
from armlab.store import MAX_PROGRAM_NAME_CHARS, Program

IMPORT_FORMATS = ("rosbag2", "jointdata", "csv", "json")
EXPORT_FORMATS = ("rosbag2", "csv", "json")
_SUFFIXES = {".mcap": "rosbag2", ".db3": "rosbag2", ".zip": "rosbag2", ".csv": "csv", ".json": "json", ".txt": "jointdata"}


@dataclass(frozen=True)
class Imported:
    """A stored program and how it was made: notes (one line each), the clamping done ({joint: largest
    correction, rad}, how many samples), how many samples were read (0 for CSV and JSON)."""

    program: Program
    notes: list[str] = field(default_factory=list)
    clamped_rad: dict[str, float] = field(default_factory=dict)
    clamped_samples: int = 0
    samples: int = 0


def guess_format(path: str | Path) -> str:
    """The import format a path's name implies (a folder: a rosbag2 bag); InvalidInput when it implies none."""
    path = Path(path)
    if path.is_dir():
        return "rosbag2"
    if path.suffix.lower() in _SUFFIXES:
        return _SUFFIXES[path.suffix.lower()]
    raise InvalidInput(f"{path}: cannot tell its format from the name; give one of {', '.join(IMPORT_FORMATS)}")


def finger_range_m(station: Station) -> tuple[float, float] | None:
    """(closed, open) finger offsets (m) of a finger gripper, None otherwise (the bag then carries `gripper`)."""
    gripper = getattr(getattr(station.model, "config", None), "gripper", None)
    return None if gripper is None else (float(gripper.finger_offset_min_m), float(gripper.finger_offset_max_m))


def joint_states_topic(station: Station) -> str:
    arm = getattr(getattr(station.model, "config", None), "name", None) or "arm"
    return f"/{arm}/joint_states"


def import_program_file(station: Station, file_format: str, *, path: str | Path | None = None, data: bytes | None = None,
                        name: str | None = None, options: ImportOptions | None = None, topic: str | None = None) -> Imported:
    """Store the file (a path, or an upload's bytes) as a new program of this station's arm; ProgramFileError
    (what is wrong, where), InvalidInput, UnsafeTrajectory: nothing stored."""
    station.require_arm("importing a program (its waypoints are checked against the arm)")
    if file_format not in IMPORT_FORMATS:
        raise InvalidInput(f"format must be one of {', '.join(IMPORT_FORMATS)}, not {file_format!r}")
    if (path is None) == (data is None):
        raise InvalidInput("give the file's path or its bytes")
    source = Path(path).name if path is not None else None
    if file_format in ("csv", "json"):
        program = import_program(station, file_format, _text(path, data, file_format), name or _stem(source))
        return Imported(program, [f"read {len(program.waypoints)} waypoints ({file_format})"])
    model = station.model
    if file_format == "jointdata":
        samples = program_formats.parse_jointdata(_text(path, data, file_format), int(model.dof))
    elif path is not None:
        samples = program_formats.read_joint_states(path, model.joint_names, finger_range_m(station), topic)
    else:
        samples = program_formats.read_joint_states_bytes(data, model.joint_names, finger_range_m(station), topic)
    converted = program_formats.to_program(samples, list(model.joint_names), model.lower_rad, model.upper_rad, options)
    check_waypoints(station, converted.waypoints)
    program = station.store.save_program(name or _stem(source) or f"imported {file_format}", converted.waypoints,
                                         owner=station.program_owner)
    return Imported(program, converted.notes, converted.clamped_rad, converted.clamped_samples, converted.samples)


def _stem(source: str | None) -> str | None:
    if not source:
        return None
    return Path(source).stem.strip()[:MAX_PROGRAM_NAME_CHARS] or None


def _text(path, data: bytes | None, file_format: str) -> str:
    raw = Path(path).read_bytes() if path is not None and not Path(path).is_dir() else data
    if raw is None:
        raise program_io.ProgramFileError(f"{path} is a folder, not a {file_format} file (a bag folder is format rosbag2)")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise program_io.ProgramFileError(f"not UTF-8 text, so not a {file_format} file (a ROS 2 bag is format rosbag2)") from None


def export_program_file(station: Station, program_id: int, file_format: str) -> tuple[bytes, str, str]:
    """(file bytes, suggested file name, media type) of a program: a ROS 2 bag as one MCAP file, CSV or JSON."""
    if file_format in ("json", "csv"):
        text, filename = export_program(station, program_id, file_format)
        return text.encode("utf-8"), filename, "application/json" if file_format == "json" else "text/csv"
    if file_format != "rosbag2":
        raise InvalidInput(f"format must be one of {', '.join(EXPORT_FORMATS)}, not {file_format!r}")
    program, rows = _program_rows(station, program_id)
    data = program_formats.joint_states_bytes(rows, station.model.joint_names, finger_range_m(station), joint_states_topic(station),
                                              _start_ns(program))
    return data, f"{_file_stem(program)}.mcap", "application/octet-stream"


def export_program_path(station: Station, program_id: int, file_format: str, out: str | Path, storage: str = "mcap") -> Path:
    """Write a program to `out` (refused if it exists): rosbag2 as a bag folder, or one MCAP file when out ends
    in .mcap; CSV or JSON as text."""
    out = Path(out)
    if file_format == "rosbag2":
        program, rows = _program_rows(station, program_id)
        return program_formats.write_joint_states(out, rows, station.model.joint_names, finger_range_m(station),
                                                  joint_states_topic(station), storage, _start_ns(program))
    data, _, _ = export_program_file(station, program_id, file_format)
    try:
        with out.open("xb") as handle:
            handle.write(data)
    except FileExistsError:
        raise InvalidInput(f"{out} exists already: give a new path") from None
    return out


def trace_bag(station: Station, samples: Sequence[Sequence[float]], joint_names: Sequence[str]) -> bytes:
    """A repeat's cycle trace ([t_s, commanded..., measured...] rows) as one MCAP file: measured joint states on
    /<arm>/joint_states, commanded on /<arm>/commanded/joint_states."""
    arm = joint_states_topic(station).split("/")[1]
    return program_formats.write_trace(None, samples, joint_names, arm)


def _program_rows(station: Station, program_id: int):
    station.require_arm("exporting a program (its joints and move times are the arm's)")
    program = get_program(station, program_id)
    return program, program_io.timed_rows(program.waypoints, move_times_s(station, program.waypoints))


def _start_ns(program: Program) -> int:
    return int(round((program.updated_s or program.created_s) * 1e9))


def _file_stem(program: Program) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in program.name)[:60] or f"program-{program.id}"
