"""Recorded joint samples (a ROS 2 bag's joint states, the course's text files) as a taught program's waypoints.

A recording is `JointSamples`: times (s, or None for untimed rows), the arm's joints per sample (rad, in the
arm's joint order) and the gripper command per sample. `to_program` checks every sample against the joint
limits (refused, or clamped by at most `clamp_rad` when the caller asks: the result says how much) and then
keeps, in either mode:

- the first and the last sample;
- holds: in a run of samples within `hold_tol_rad` of its first one with one gripper command, the samples
  around its middle one within half of hold_tol_rad of it, lasting at least `hold_min_s` (or repeating the
  very same joints, as a program's own export does): a waypoint at the middle sample's joints whose dwell_s is
  the hold's duration (the approach and the departure around it are path);
- gripper steps: where the command changes, the last sample before (unless a hold already stands there) and
  the first after; when the arm stood still (within hold_tol_rad) the step keeps the joints before it exactly,
  so the program has a gripper step, not a move.

Between those, mode "waypoints" thins the path (Ramer-Douglas-Peucker in joint space: a sample is kept when
the path would otherwise pass more than `path_tol_rad` from it, on some joint); mode "trajectory" keeps every
sample that moved `min_change_rad` on some joint since the last one kept (as teach's continuous recorder does).
A kept waypoint's moving_time_s is the time since the previous one was left (after its dwell); untimed rows
give no move times and no dwells. Pure functions: no station, no database.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from armlab.program_io import MAX_WAYPOINTS, SAME_JOINTS_RAD, ProgramFileError
from armlab.store import MAX_DWELL_S, Waypoint

MODES = ("waypoints", "trajectory")


@dataclass(frozen=True)
class JointSamples:
    """A recording: times_s (n,) from its first sample (None: untimed rows), positions_rad (n, dof) in the
    arm's joint order, gripper[i] 'grasp' | 'release'; notes: what reading it assumed (one line each)."""

    times_s: np.ndarray | None
    positions_rad: np.ndarray
    gripper: tuple[str, ...]
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class ImportOptions:
    """How samples become waypoints (see the module's docstring)."""

    mode: str = "waypoints"
    clamp_rad: float = 0.0  # 0: a sample beyond a joint limit refuses the file; > 0: clamp excesses up to this, refuse beyond
    path_tol_rad: float = 0.02
    min_change_rad: float = 0.01
    hold_tol_rad: float = 0.005
    hold_min_s: float = 0.25

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ProgramFileError(f"mode must be one of {', '.join(MODES)}, not {self.mode!r}")
        for name in ("clamp_rad", "path_tol_rad", "min_change_rad", "hold_tol_rad", "hold_min_s"):
            value = float(getattr(self, name))
            if not (np.isfinite(value) and 0.0 <= value <= (1.0 if name != "hold_min_s" else 60.0)):
                raise ProgramFileError(f"{name} must be from 0 to {1.0 if name != 'hold_min_s' else 60.0:g}, not {value!r}")


@dataclass(frozen=True)
class Converted:
    """The waypoints of a recording and what was done to get them: notes (one line each), clamped
    ({joint: the largest correction, rad}) and how many samples were clamped."""

    waypoints: list[Waypoint]
    samples: int
    notes: list[str] = field(default_factory=list)
    clamped_rad: dict[str, float] = field(default_factory=dict)
    clamped_samples: int = 0


def to_program(samples: JointSamples, joint_names: Sequence[str], lower_rad, upper_rad,
               options: ImportOptions | None = None) -> Converted:
    """The recording's waypoints after the limit check (ProgramFileError naming the joint, the sample and
    the limit; nothing is returned, so nothing is stored)."""
    options = options or ImportOptions()
    positions = np.asarray(samples.positions_rad, dtype=float)
    if positions.ndim != 2 or len(positions) == 0:
        raise ProgramFileError("the recording has no joint samples")
    if positions.shape[1] != len(joint_names):
        raise ProgramFileError(f"the samples have {positions.shape[1]} joints; the arm has {len(joint_names)} ({', '.join(joint_names)})")
    if not np.all(np.isfinite(positions)):
        row = int(np.argwhere(~np.isfinite(positions))[0][0])
        raise ProgramFileError(f"sample {row + 1}{_at(samples.times_s, row)}: a joint position is not a finite number")
    positions, clamped, count = _limited(positions, samples.times_s, joint_names, lower_rad, upper_rad, options.clamp_rad)
    waypoints = _waypoints(JointSamples(samples.times_s, positions, samples.gripper), options)
    notes = list(samples.notes)
    if count:
        notes.append(f"clamped {count} of {len(positions)} samples into the joint limits: "
                     + ", ".join(f"{name} by up to {amount:.4f} rad" for name, amount in clamped.items()))
    notes.append(f"{len(positions)} samples -> {len(waypoints)} waypoints ({options.mode})")
    return Converted(waypoints, len(positions), notes, clamped, count)


def _at(times_s, row: int) -> str:
    return f" (t = {float(times_s[row]):.3f} s)" if times_s is not None else ""


def _limited(positions: np.ndarray, times_s, joint_names, lower_rad, upper_rad, clamp_rad: float):
    """(positions inside the limits, {joint: largest correction}, samples clamped); ProgramFileError for a sample
    beyond a limit (by more than clamp_rad)."""
    lower, upper = np.asarray(lower_rad, dtype=float), np.asarray(upper_rad, dtype=float)
    excess = np.maximum(positions - upper, lower - positions)  # > 0: beyond a limit, by this much
    beyond = excess > 1e-9
    if not beyond.any():
        return positions, {}, 0
    refused = excess > clamp_rad + 1e-9
    if refused.any():
        row, joint = (int(v) for v in np.unravel_index(int(np.argmax(excess)), excess.shape))  # the worst sample
        value = positions[row, joint]
        how = "" if clamp_rad <= 0 else f", more than the {clamp_rad:g} rad clamp allows"
        raise ProgramFileError(
            f"sample {row + 1}{_at(times_s, row)}: joint '{joint_names[joint]}' = {value:.4f} rad is outside its limits "
            f"[{lower[joint]:.4f}, {upper[joint]:.4f}] rad by {excess[row, joint]:.4f} rad{how} ({int(refused.sum())} values "
            f"beyond in all); nothing was stored" + ("" if clamp_rad > 0 else " (clamping needs an explicit clamp amount)")
        )
    clamped = {joint_names[j]: float(excess[:, j].max()) for j in range(len(joint_names)) if beyond[:, j].any()}
    return np.clip(positions, lower, upper), clamped, int(beyond.any(axis=1).sum())


def _runs(positions: np.ndarray, gripper: Sequence[str], tol: float) -> list[tuple[int, int]]:
    """[(first, last)] index ranges: maximal runs within tol of their first sample with one gripper command."""
    runs, start = [], 0
    for i in range(1, len(positions)):
        if gripper[i] != gripper[start] or np.max(np.abs(positions[i] - positions[start])) > tol:
            runs.append((start, i - 1))
            start = i
    runs.append((start, len(positions) - 1))
    return runs


def _rdp(positions: np.ndarray, first: int, last: int, tol: float, keep: set[int]) -> None:
    """Ramer-Douglas-Peucker between two kept samples: keep the sample farthest (Euclidean, in joint space) from
    the straight joint-space segment between them while it is more than tol away, and recurse on both halves."""
    stack = [(first, last)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        start, direction = positions[a], positions[b] - positions[a]
        length2 = float(direction @ direction)
        offsets = positions[a + 1 : b] - start
        along = np.clip(offsets @ direction / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(offsets))
        deviation = np.linalg.norm(offsets - along[:, None] * direction, axis=1)
        k = int(np.argmax(deviation))
        if deviation[k] > tol:
            keep.add(a + 1 + k)
            stack.extend([(a, a + 1 + k), (a + 1 + k, b)])


def _holds(samples: JointSamples, runs: list[tuple[int, int]], options: ImportOptions) -> dict[int, tuple[int, int]]:
    """{arrival index: (last index, pose index)} of each hold. In a run, the arm's pose is its middle sample's; the
    hold is the samples around it within half of hold_tol_rad of it (the approach and the departure before and
    after are path, not dwell), lasting hold_min_s (or repeating the very same joints)."""
    positions, times = samples.positions_rad, samples.times_s
    holds = {}
    for first, last in runs:
        if last == first:
            continue
        middle = (first + last) // 2
        near = np.max(np.abs(positions[first : last + 1] - positions[middle]), axis=1) <= options.hold_tol_rad / 2
        arrival, end = middle, middle
        while arrival > first and near[arrival - 1 - first]:
            arrival -= 1
        while end < last and near[end + 1 - first]:
            end += 1
        same = np.max(np.abs(positions[arrival : end + 1] - positions[middle])) <= SAME_JOINTS_RAD
        long_enough = times is not None and times[end] - times[arrival] >= options.hold_min_s
        if end > arrival and (long_enough or same):
            holds[arrival] = (end, middle)
    return holds


def _waypoints(samples: JointSamples, options: ImportOptions) -> list[Waypoint]:
    positions, gripper, times = samples.positions_rad, samples.gripper, samples.times_s
    runs = _runs(positions, gripper, options.hold_tol_rad)
    holds = _holds(samples, runs, options)  # arrival index -> (last index, pose index)
    keep = {0, len(positions) - 1, *holds}
    for (_, last_a), (first_b, _) in zip(runs, runs[1:]):
        if gripper[last_a] != gripper[first_b]:
            keep.add(first_b)
            if not any(last_a == end for end, _ in holds.values()):
                keep.add(last_a)
    anchors = sorted(keep)
    for a, b in zip(anchors, anchors[1:]):
        start = holds[a][0] if a in holds else a  # a hold's samples are its waypoint's dwell, not path
        if options.mode == "waypoints":
            _rdp(positions, start, b, options.path_tol_rad, keep)
        else:
            last_kept = positions[a]
            for i in range(start + 1, b):
                if np.max(np.abs(positions[i] - last_kept)) >= options.min_change_rad:
                    keep.add(i)
                    last_kept = positions[i]
    waypoints: list[Waypoint] = []
    lefts: list[float | None] = []  # left_s before each waypoint was added
    left_s = None  # when the arm left the previous waypoint (after its dwell)
    for i in sorted(keep):
        if any(first < i <= end for first, (end, _) in holds.items()):
            continue  # inside a hold: its first sample's dwell covers it
        joints = tuple(float(v) for v in positions[holds[i][1] if i in holds else i])  # a hold: where the arm stood
        while i in holds and len(waypoints) > 1 and waypoints[-1].gripper == gripper[i] and _near(waypoints[-1], joints, options):
            waypoints.pop()  # a path sample just short of a hold: the hold's pose stands for it
            left_s = lefts.pop()
        previous = waypoints[-1] if waypoints else None
        still = previous is not None and _near(previous, joints, options)
        if still and gripper[i] == previous.gripper:
            continue  # the same pose and command again: nothing to do there
        if still:
            joints = previous.joints_rad  # a gripper step where the arm stood
        dwell = 0.0
        if times is not None and i in holds:
            dwell = min(float(times[holds[i][0]] - times[i]), MAX_DWELL_S)
        moving = None
        if times is not None and left_s is not None and not still:
            gap = float(times[i]) - left_s
            if gap > MAX_DWELL_S:
                raise ProgramFileError(f"sample {i + 1}{_at(times, i)}: a move of {gap:.0f} s; at most {MAX_DWELL_S:g} s")
            moving = gap if gap > 1e-6 else None
        waypoints.append(Waypoint(joints, gripper[i], dwell, moving))
        lefts.append(left_s)
        if times is not None:
            left_s = float(times[i]) + dwell
        if len(waypoints) > MAX_WAYPOINTS:
            raise ProgramFileError(f"the recording makes more than {MAX_WAYPOINTS} waypoints ({options.mode}); thin it "
                                   "(mode waypoints, or a larger min_change_rad / path_tol_rad)")
    return waypoints


def _near(waypoint: Waypoint, joints, options: ImportOptions) -> bool:
    return max(abs(p - q) for p, q in zip(waypoint.joints_rad, joints)) <= options.hold_tol_rad
