"""Scoring block detections on hand-labelled real frames (the ROB 550 *.labels.json format): labels
read and checked, detections matched to labelled cubes by pixel distance, and per-frame counts
(found, colour/size/stack level right, extras, distractors called cubes, centre and height errors).
Pure functions: bench/real_frames.py runs the detector and prints what these return."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# Label colour names -> the project's class names (the labels say "purple", config/vision.yaml "violet").
LABEL_COLOURS = {"purple": "violet"}


@dataclass(frozen=True)
class LabelledCube:
    """One hand-labelled cube: its top face's centre pixel and what a detector should say about it.

    occluded: a lower stack member whose top is hidden (a detector reports stack tops only);
    uncertain: the labeller's guess; other: a cube of a colour outside the classes (black, pink)."""

    color: str
    size: str
    u: float
    v: float
    stacked: bool = False
    occluded: bool = False
    uncertain: bool = False
    other: bool = False
    depth_height_mm: float | None = None
    stack_level: int = 1


@dataclass(frozen=True)
class FrameLabels:
    image: str
    cubes: tuple[LabelledCube, ...]
    distractors_uv: tuple[tuple[float, float], ...] = ()
    tags: tuple[tuple[int, float, float, bool], ...] = ()  # (id, u, v, occluded) of the board tags labelled

    def false_tags(self, found: list[tuple[int, float, float]], radius_px: float = 8.0) -> list[int]:
        """Ids of decoded tags (id, u, v) that are no labelled tag: an unknown id or far from where it is."""
        known = {t[0]: (t[1], t[2]) for t in self.tags}
        return [i for i, u, v in found if i not in known or math.hypot(u - known[i][0], v - known[i][1]) > radius_px]


def _stack_levels(cubes: list[LabelledCube], radius_px: float) -> list[int]:
    """Level of each label: 1 when it stands on the board, else 1 + the labelled cubes under it (within
    radius_px of it in the image: the lower members of a stack project next to its top)."""
    levels = []
    for i, cube in enumerate(cubes):
        if not cube.stacked:
            levels.append(1)
            continue
        under = sum(1 for j, other in enumerate(cubes) if j != i and math.hypot(other.u - cube.u, other.v - cube.v) <= radius_px
                    and (other.occluded or not other.stacked or other.depth_height_mm is None))
        levels.append(1 + max(1, under))
    return levels


def load_labels(path: str | Path, stack_radius_px: float = 40.0) -> FrameLabels:
    """A frame's labels (image_<name>.labels.json). ValueError naming the file and field when malformed."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise ValueError(f"cannot read labels {path}: {error}") from error
    if not isinstance(data, dict) or not isinstance(data.get("cubes"), list):
        raise ValueError(f"labels {path}: expected a JSON object with a 'cubes' list")
    cubes = []
    for key, other in (("cubes", False), ("other_cubes", True)):
        for i, item in enumerate(data.get(key, [])):
            try:
                colour = str(item["color"])
                cubes.append(LabelledCube(
                    color=LABEL_COLOURS.get(colour, colour), size=str(item["size"]), u=float(item["u"]), v=float(item["v"]),
                    stacked=bool(item.get("stacked_on_another", False)), occluded=bool(item.get("occluded", False)),
                    uncertain=bool(item.get("uncertain", False)), other=other,
                    depth_height_mm=None if item.get("depth_height_mm") is None else float(item["depth_height_mm"]),
                ))
            except (KeyError, TypeError, ValueError) as error:
                raise ValueError(f"labels {path}: {key}[{i}] is malformed ({error!r})") from error
    levels = _stack_levels(cubes, stack_radius_px)
    cubes = [LabelledCube(**{**c.__dict__, "stack_level": level}) for c, level in zip(cubes, levels)]
    distractors = tuple((float(d["u"]), float(d["v"])) for key in ("distractors", "occluders") for d in data.get(key, [])
                        if isinstance(d, dict) and "u" in d and "v" in d)
    try:
        tags = tuple(sorted((int(t["id"]), float(t["u"]), float(t["v"]), bool(t.get("occluded", False))) for t in data.get("apriltags", [])))
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"labels {path}: apriltags is malformed ({error!r})") from error
    return FrameLabels(str(data.get("image", path.name)), tuple(cubes), distractors, tags)


def match_by_distance(a_uv: np.ndarray, b_uv: np.ndarray, radius_px: float) -> list[tuple[int, int]]:
    """Pairs (i, j) of points a_uv[i] and b_uv[j] closer than radius_px, closest pairs first, each point
    used at most once (greedy assignment: with points far apart relative to the radius, as cubes are,
    it equals the optimal one)."""
    a = np.asarray(a_uv, dtype=float).reshape(-1, 2)
    b = np.asarray(b_uv, dtype=float).reshape(-1, 2)
    if len(a) == 0 or len(b) == 0:
        return []
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    pairs, used_a, used_b = [], set(), set()
    for flat in np.argsort(d, axis=None, kind="stable"):
        i, j = divmod(int(flat), d.shape[1])
        if d[i, j] > radius_px:
            break
        if i not in used_a and j not in used_b:
            pairs.append((i, j))
            used_a.add(i)
            used_b.add(j)
    return pairs


@dataclass(frozen=True)
class Detection:
    """What the scorer needs from a detected block: pixel, class, stack level, height and world centre."""

    u: float
    v: float
    color: str
    size: str
    stack_level: int
    height_mm: float
    xy_mm: tuple[float, float]


@dataclass
class FrameScore:
    """Counts on one frame. Sure labels = visible, not uncertain, of a known colour: the targets' base."""

    labelled: int = 0  # sure labels
    found: int = 0
    color_right: int = 0
    size_right: int = 0
    level_right: int = 0
    uncertain_labelled: int = 0
    uncertain_found: int = 0
    other_labelled: int = 0  # cubes of colours outside the classes
    other_found: int = 0
    hidden_members: int = 0  # occluded lower stack members (not expected)
    extras: int = 0  # cubes reported where no cube is labelled
    distractors_called_cubes: int = 0
    centre_errors_px: list[float] = field(default_factory=list)
    centre_errors_mm: list[float] = field(default_factory=list)
    height_errors_mm: list[float] = field(default_factory=list)
    misses: list[str] = field(default_factory=list)
    wrong: list[str] = field(default_factory=list)

    def add(self, other: FrameScore) -> None:
        for name, value in other.__dict__.items():
            setattr(self, name, getattr(self, name) + value)


def score_frame(labels: FrameLabels, detections: list[Detection], radius_px: float, mm_per_px: float) -> FrameScore:
    """Match detected cubes to labels within radius_px and count. A detection on an occluded label
    (a lower stack member) is neither an extra nor required; mm_per_px turns pixel centre errors into mm
    (the board's scale at the detections' distance)."""
    s = FrameScore()
    cubes = list(labels.cubes)
    visible = [c for c in cubes if not c.occluded]
    s.hidden_members = len(cubes) - len(visible)
    s.labelled = sum(1 for c in visible if not c.uncertain and not c.other)
    s.uncertain_labelled = sum(1 for c in visible if c.uncertain and not c.other)
    s.other_labelled = sum(1 for c in visible if c.other)
    det_uv = np.array([[d.u, d.v] for d in detections]).reshape(-1, 2)
    # Visible labels first, then whatever detections are left may sit on hidden members.
    pairs = match_by_distance(det_uv, np.array([[c.u, c.v] for c in visible]).reshape(-1, 2), radius_px)
    matched = {i for i, _ in pairs}
    found_labels = set()
    for i, j in pairs:
        det, cube = detections[i], visible[j]
        found_labels.add(j)
        if cube.other:
            s.other_found += 1
            continue
        if cube.uncertain:
            s.uncertain_found += 1
            continue
        s.found += 1
        s.color_right += det.color == cube.color
        s.size_right += det.size == cube.size
        s.level_right += det.stack_level == cube.stack_level
        err_px = math.hypot(det.u - cube.u, det.v - cube.v)
        s.centre_errors_px.append(err_px)
        s.centre_errors_mm.append(err_px * mm_per_px)
        if cube.depth_height_mm is not None:
            s.height_errors_mm.append(det.height_mm - cube.depth_height_mm)
        if (det.color, det.size, det.stack_level) != (cube.color, cube.size, cube.stack_level):
            s.wrong.append(f"({cube.u:.0f},{cube.v:.0f}) {cube.color} {cube.size} L{cube.stack_level} "
                           f"read {det.color} {det.size} L{det.stack_level}")
    s.misses = [f"({c.u:.0f},{c.v:.0f}) {c.color} {c.size}" for j, c in enumerate(visible)
                if j not in found_labels and not c.uncertain and not c.other]
    rest = [i for i in range(len(detections)) if i not in matched]
    hidden = [c for c in cubes if c.occluded]
    on_hidden = {i for i, _ in match_by_distance(det_uv[rest], np.array([[c.u, c.v] for c in hidden]).reshape(-1, 2), radius_px)}
    rest = [k for n, k in enumerate(rest) if n not in on_hidden]
    on_distractor = {n for n, _ in match_by_distance(det_uv[rest], np.array(labels.distractors_uv).reshape(-1, 2), 2 * radius_px)}
    s.distractors_called_cubes = len(on_distractor)
    s.extras = len(rest) - len(on_distractor)
    s.wrong += [f"extra ({detections[k].u:.0f},{detections[k].v:.0f}) {detections[k].color} {detections[k].size} "
                f"{detections[k].height_mm:.0f} mm" for n, k in enumerate(rest) if n not in on_distractor]
    return s
