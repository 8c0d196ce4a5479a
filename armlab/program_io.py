"""Taught programs as files: JSON (everything) and CSV (`t_s, q1..qn, gripper`, radians), both ways.

JSON keeps everything, a program's step tree (waits, gripper steps, loops, groups: armlab.store.program_tree) too:
"steps" holds the tree (format version 2) and "waypoints" its expanded sequence, so a reader that knows only
waypoints imports the same motion. CSV (and the ROS 2 bag export) is flat: it holds the expanded sequence
(loops unrolled, waits as dwells, gripper steps as rows); importing it gives a flat program.

CSV rows are the timed path: t_s is when the waypoint is reached (the first row at 0), q1..qn its joints
in radians, gripper `grasp` or `release`. A row whose joints and gripper equal the previous row's is a
dwell there (its t_s gap); a row with the previous row's joints and the other gripper command is a gripper
step; any other row is a move whose moving_time_s is its t_s gap (0 = as fast as allowed). Parsing
refuses the whole file at the first problem with ProgramFileError naming the line and the reason, so a
malformed import changes nothing. Pure functions: no station, no database.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Sequence

from armlab.errors import InvalidInput
from armlab.store import MAX_PROGRAM_NAME_CHARS, Waypoint, program_tree

FORMAT_NAME = "armlab-program"
FORMAT_VERSION = 1  # a flat program; 2: with "steps" (the step tree)
MAX_WAYPOINTS = 1000
SAME_JOINTS_RAD = 1e-9  # rows this close are "the same joints" (a dwell or a gripper step)


def file_number(text: str, line: int, what: str) -> float:
    """A finite number from a program file's cell, else ProgramFileError naming the line and the field."""
    try:
        value = float(text)
    except ValueError:
        raise ProgramFileError(f"line {line}: {what} = {text.strip()!r} is not a number") from None
    if not math.isfinite(value):
        raise ProgramFileError(f"line {line}: {what} = {text.strip()!r} is not finite")
    return value


class ProgramFileError(InvalidInput):
    """A program file that cannot be imported; the message names the line (CSV) or the item (JSON) and why."""


def to_json(name: str, waypoints: Sequence[Waypoint], joint_names: Sequence[str], steps: Sequence | None = None) -> str:
    """The program as a JSON document (round-trips through parse_json); steps: its step tree, if it has one
    (waypoints is then the tree expanded)."""
    document = {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION if steps is None else 2,
        "name": name,
        "joint_names": list(joint_names),
        "waypoints": [waypoint.to_dict() for waypoint in waypoints],
    }
    if steps is not None:
        document["steps"] = program_tree.to_list(steps)
    return json.dumps(document, indent=1)


def to_csv(waypoints: Sequence[Waypoint], move_times_s: Sequence[float]) -> str:
    """The program as CSV. move_times_s[i]: the planned duration of the move into waypoint i (the first is
    ignored: t_s starts at 0); a dwell adds a repeated row."""
    out = io.StringIO()
    dof = len(waypoints[0].joints_rad) if waypoints else 0
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["t_s", *(f"q{i + 1}" for i in range(dof)), "gripper"])
    for t_s, joints, gripper in timed_rows(waypoints, move_times_s):
        writer.writerow([f"{t_s:.6f}", *(f"{q:.9f}" for q in joints), gripper])
    return out.getvalue()


def timed_rows(waypoints: Sequence[Waypoint], move_times_s: Sequence[float]) -> list[tuple[float, tuple[float, ...], str]]:
    """The program's timed path, one (t_s, joints_rad, gripper) per CSV row: a row when each waypoint is reached
    (move_times_s[i]: the move into waypoint i; the first is ignored, t_s starts at 0) and one more when its
    dwell ends. The CSV export and the ROS 2 bag export (armlab.program_formats) write these rows."""
    rows, t_s = [], 0.0
    for index, waypoint in enumerate(waypoints):
        if index > 0:
            t_s += float(move_times_s[index])
        rows.append((t_s, waypoint.joints_rad, waypoint.gripper))
        if waypoint.dwell_s > 0:
            t_s += waypoint.dwell_s
            rows.append((t_s, waypoint.joints_rad, waypoint.gripper))
    return rows


def parse_json(text: str, dof: int) -> tuple[str | None, list]:
    """(name or None, waypoints) from a JSON document of to_json's form (or a bare list of waypoints); a
    document with "steps" gives its step tree instead (checked: limits, joint counts; expand it to plan)."""
    try:
        document = json.loads(text)
    except json.JSONDecodeError as error:
        raise ProgramFileError(f"line {error.lineno}: not valid JSON ({error.msg})") from None
    except RecursionError:
        raise ProgramFileError("the JSON is nested too deeply to be a program file") from None
    name = None
    if isinstance(document, dict):
        if document.get("format", FORMAT_NAME) != FORMAT_NAME:
            raise ProgramFileError(f"'format' is {document.get('format')!r}, not {FORMAT_NAME!r}")
        name = document.get("name")
        if name is not None and not isinstance(name, str):
            raise ProgramFileError("'name' must be a string")
        if name is not None and len(name.strip()) > MAX_PROGRAM_NAME_CHARS:
            raise ProgramFileError(f"'name' has {len(name.strip())} characters; at most {MAX_PROGRAM_NAME_CHARS}")
        if document.get("steps") is not None:
            return name, _parse_steps(document["steps"], dof)
        items = document.get("waypoints")
    else:
        items = document
    if not isinstance(items, list):
        raise ProgramFileError("'waypoints' must be a list")
    _check_count(len(items))
    waypoints = []
    for index, item in enumerate(items):
        where = f"waypoint {index + 1}"
        if not isinstance(item, dict) or "joints_rad" not in item or "gripper" not in item:
            raise ProgramFileError(f"{where}: needs 'joints_rad' and 'gripper'")
        joints = item["joints_rad"]
        if not isinstance(joints, list) or not all(_is_number(v) for v in joints):
            raise ProgramFileError(f"{where}: 'joints_rad' must be a list of numbers (finite)")
        if len(joints) != dof:
            raise ProgramFileError(f"{where}: {len(joints)} joint values, the arm has {dof}")
        for key in ("dwell_s", "moving_time_s"):
            if item.get(key) is not None and not _is_number(item[key]):
                raise ProgramFileError(f"{where}: '{key}' must be a number (finite)")
        unknown = set(item) - {"joints_rad", "gripper", "dwell_s", "moving_time_s"}
        if unknown:
            raise ProgramFileError(f"{where}: unknown field(s) {', '.join(sorted(unknown))}")
        try:
            waypoints.append(Waypoint.from_dict(item))
        except (KeyError, TypeError, ValueError) as error:
            raise ProgramFileError(f"{where}: {error}") from None
    return name, waypoints


def parse_csv(text: str, dof: int) -> list[Waypoint]:
    """Waypoints from CSV of to_csv's form: header `t_s, q1..q<dof>, gripper`, one row per line."""
    reader = csv.reader(io.StringIO(text))
    try:
        rows = list(reader)
    except csv.Error as error:  # e.g. a field over csv's field_size_limit (131,072 characters), an unclosed quote
        raise ProgramFileError(f"line {reader.line_num}: {error}") from None
    expected = ["t_s", *(f"q{i + 1}" for i in range(dof)), "gripper"]
    if not rows:
        raise ProgramFileError("line 1: the file is empty; expected the header " + ",".join(expected))
    header = [cell.strip() for cell in rows[0]]
    if header != expected:
        raise ProgramFileError(f"line 1: the header is {','.join(header)!r}; expected {','.join(expected)!r}")
    waypoints: list[Waypoint] = []
    previous_t = None
    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != len(expected):
            raise ProgramFileError(f"line {line}: {len(row)} values, expected {len(expected)} ({','.join(expected)})")
        values = []
        for column, cell in zip(expected[:-1], row[:-1]):
            values.append(file_number(cell, line, column))
        gripper = row[-1].strip()
        if gripper not in ("grasp", "release"):
            raise ProgramFileError(f"line {line}: gripper = {gripper!r}; expected 'grasp' or 'release'")
        t_s, joints = values[0], tuple(values[1:])
        if previous_t is None and t_s != 0.0:
            raise ProgramFileError(f"line {line}: the first t_s must be 0, not {t_s:g}")
        if previous_t is not None and t_s < previous_t:
            raise ProgramFileError(f"line {line}: t_s = {t_s:g} goes back in time (previous row {previous_t:g})")
        gap_s = 0.0 if previous_t is None else t_s - previous_t
        previous_t = t_s
        last = waypoints[-1] if waypoints else None
        same_joints = last is not None and max(abs(a - b) for a, b in zip(last.joints_rad, joints)) <= SAME_JOINTS_RAD
        try:
            if same_joints and gripper == last.gripper:  # a dwell on the previous waypoint
                waypoints[-1] = Waypoint(last.joints_rad, last.gripper, last.dwell_s + gap_s, last.moving_time_s)
                continue
            moving_time_s = gap_s if gap_s > 0 and not same_joints else None
            waypoints.append(Waypoint(joints, gripper, 0.0, moving_time_s))
        except ValueError as error:
            raise ProgramFileError(f"line {line}: {error}") from None
        _check_count(len(waypoints))
    if not waypoints:
        raise ProgramFileError("the file has a header but no waypoints")
    return waypoints


def _parse_steps(items, dof: int) -> list:
    """A document's step tree, checked (ProgramFileError naming the step: steps[2].body[0].count ...)."""
    try:
        steps = program_tree.steps_from_list(items)
        waypoints = program_tree.expand(steps)
    except InvalidInput as error:
        raise ProgramFileError(str(error)) from None
    for index, waypoint in enumerate(waypoints):
        if len(waypoint.joints_rad) != dof:
            raise ProgramFileError(f"steps: expanded waypoint {index + 1} has {len(waypoint.joints_rad)} joint values, the arm has {dof}")
    return list(steps)


def _check_count(count: int) -> None:
    if count == 0:
        raise ProgramFileError("the program has no waypoints")
    if count > MAX_WAYPOINTS:
        raise ProgramFileError(f"the program has more than {MAX_WAYPOINTS} waypoints")


def _is_number(value) -> bool:
    """A finite JSON number (an integer too large for a float, such as 10**400, is not)."""
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False
