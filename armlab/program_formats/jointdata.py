"""The ROB 550 course's joint text files (format "jointdata"), radians, one sample a line:

- timed lines `t, [q1, ..., qn, gripper]` (t in seconds; the bracket may also hold only the n joints;
  gripper 1 = closed = 'grasp', 0 = open = 'release', or one of the words below);
- rows of n angles, as numpy prints an array (`[ 0.0046 -1.7963 -1.6291 -0.5998  0.0245]`, also wrapped over
  lines) or separated by commas or spaces, untimed; a line `Open` or `Close` (also release/grasp, opened/closed) sets the gripper for
  the rows after it (the course's recorders print these between rows).

Blank lines and lines starting with # are skipped. A file is all timed or all untimed lines. Any other line
refuses the file (ProgramFileError naming the line). Pure: no station, no database.
"""

from __future__ import annotations

import re

import numpy as np

from armlab.program_formats.samples import JointSamples
from armlab.program_io import ProgramFileError, file_number

MAX_LINES = 2_000_000
OPEN_WORDS = ("open", "opened", "release", "released")
CLOSE_WORDS = ("close", "closed", "grasp", "grasped")
_TIMED = re.compile(r"^\s*([^\[\],]+?)\s*,?\s*\[(.*)\]\s*,?\s*$")


def parse_jointdata(text: str, dof: int) -> JointSamples:
    """Samples from the course's text; ProgramFileError naming the line and the reason."""
    times: list[float] = []
    rows: list[list[float]] = []
    grippers: list[str] = []
    gripper = "release"
    timed: bool | None = None
    lines = text.splitlines()
    if len(lines) > MAX_LINES:
        raise ProgramFileError(f"the file has more than {MAX_LINES} lines")
    for number, line in _logical_lines(lines):
        if not line or line.startswith("#"):
            continue
        word = line.lower().strip(" .,;:")
        if word in OPEN_WORDS or word in CLOSE_WORDS:
            gripper = "release" if word in OPEN_WORDS else "grasp"
            continue
        match = _TIMED.match(line)
        is_timed = match is not None and not line.startswith("[")
        if timed is None:
            timed = is_timed
        elif timed != is_timed:
            raise ProgramFileError(f"line {number}: {'a timed' if is_timed else 'an untimed'} line in a file of "
                                   f"{'timed' if timed else 'untimed'} lines ({line[:60]!r})")
        if is_timed:
            t_s = file_number(match.group(1), number, "t")
            values = _numbers(match.group(2), number, allow_words=True)
            if len(values) == dof + 1:
                gripper = _gripper_value(values[-1], number)
                values = values[:-1]
            elif len(values) != dof:
                raise ProgramFileError(f"line {number}: {len(values)} values in the brackets; expected {dof} joints and the gripper")
            if any(isinstance(v, str) for v in values):
                raise ProgramFileError(f"line {number}: a word among the joint angles; the gripper comes after all {dof} joints")
            if times and t_s < times[-1]:
                raise ProgramFileError(f"line {number}: t = {t_s:g} goes back in time (previous line {times[-1]:g})")
            times.append(t_s)
        else:
            values = _numbers(line.strip("[]"), number)
            if len(values) != dof:
                raise ProgramFileError(f"line {number}: {len(values)} values; expected {dof} joint angles (rad) or `t, [q1..q{dof}, gripper]`")
        rows.append([float(v) for v in values])
        grippers.append(gripper)
    if not rows:
        raise ProgramFileError("the file has no joint rows")
    times_s = np.asarray(times) - times[0] if timed else None
    note = f"read {len(rows)} {'timed' if timed else 'untimed'} joint rows"
    return JointSamples(times_s, np.asarray(rows, dtype=float), tuple(grippers), (note,))


def _logical_lines(lines: list[str]):
    """(first line number, stripped text) with a bracket numpy wrapped over several lines joined into one."""
    pending, start = "", 0
    for number, raw in enumerate(lines, start=1):
        line = raw.strip()
        if pending:
            pending += " " + line
            if "]" in line:
                yield start, pending
                pending = ""
            continue
        if "[" in line and "]" not in line and not line.startswith("#"):
            pending, start = line, number
            continue
        yield number, line
    if pending:
        raise ProgramFileError(f"line {start}: the bracket opened here is never closed")


def _numbers(text: str, line: int, allow_words: bool = False) -> list:
    cells = [cell for cell in re.split(r"[,\s]+", text.strip()) if cell]
    values: list = []
    for index, cell in enumerate(cells):
        if allow_words and index == len(cells) - 1 and cell.lower() in (*OPEN_WORDS, *CLOSE_WORDS, "true", "false"):
            values.append(cell.lower())
        else:
            values.append(file_number(cell, line, f"value {index + 1}"))
    return values


def _gripper_value(value, line: int) -> str:
    if isinstance(value, str):
        return "grasp" if value in (*CLOSE_WORDS, "true") else "release"
    if value in (0.0, 1.0):
        return "grasp" if value == 1.0 else "release"
    raise ProgramFileError(f"line {line}: gripper = {value:g}; expected 1 (closed), 0 (open), open or close")
