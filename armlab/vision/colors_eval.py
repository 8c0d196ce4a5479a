"""Colour accuracy at hand-labelled cube centres of real frames (the rob550_dev format: image_<name>.png
with image_<name>.labels.json): each labelled top face's centre patch, normalised by the board's grey
around it, classified by a ColorModel; the confusion matrix and per-frame figures. Used by
bench/real_colors.py, bench/color_references.py and the colour tests, so the figures stand alone from
block detection (a face is read where the label puts it, not where a detector finds it).
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from armlab.vision.colors import CLICK_FACE_SIDE_PX, ColorModel, ColorReading, classify_at, measure_at

LABEL_NAMES = {"purple": "violet"}  # the labels' colour names -> the station's class names


@dataclass(frozen=True)
class LabelledFace:
    """One labelled cube's top face: frame name, colour (station names), size, centre pixel, flags."""

    frame: str
    color: str
    size: str
    u: int
    v: int
    uncertain: bool
    occluded: bool
    extra: bool  # a cube outside the six colours (the labels' other_cubes)


def read_labelled_faces(data_dir: str | Path) -> list[LabelledFace]:
    """Every labelled cube of every image_*.labels.json in data_dir (occluded ones included, flagged)."""
    faces = []
    for path in sorted(Path(data_dir).glob("image_*.labels.json")):
        labels = json.loads(path.read_text())
        frame = path.name[len("image_") : -len(".labels.json")]
        for extra, key in ((False, "cubes"), (True, "other_cubes")):
            for cube in labels.get(key, []):
                color = LABEL_NAMES.get(cube["color"], cube["color"])
                faces.append(LabelledFace(frame, color, cube.get("size", "large"), int(cube["u"]), int(cube["v"]),
                                          bool(cube.get("uncertain", False)), bool(cube.get("occluded", False)), extra))
    return faces


def face_side_px(face: LabelledFace, image_width: int) -> float:
    """About how wide the face looks (CLICK_FACE_SIDE_PX for a large cube, scaled by size and image width)."""
    return CLICK_FACE_SIDE_PX * (1.0 if face.size == "large" else 0.025 / 0.038) * image_width / 1280.0


def measure_face(model: ColorModel, color_bgr: np.ndarray, face: LabelledFace) -> np.ndarray:
    """Board-normalised CIELAB of the labelled face's centre patch (board grey from the ring around it)."""
    return measure_at(model, color_bgr, (face.u, face.v), face_side_px(face, color_bgr.shape[1]))


def classify_face(model: ColorModel, color_bgr: np.ndarray, face: LabelledFace) -> ColorReading:
    """The model's reading of the labelled face's centre patch, as detection reads a face (clipping included)."""
    return classify_at(model, color_bgr, (face.u, face.v), face_side_px(face, color_bgr.shape[1]))


@dataclass
class ColorScore:
    """Per-frame and total colour figures at the labelled centres."""

    confusion: Counter  # (label, read) -> count
    per_frame: dict  # frame -> [right, counted]
    readings: list  # (LabelledFace, ColorReading)

    @property
    def counted(self) -> int:
        return sum(n for _, n in self.per_frame.values())

    @property
    def right(self) -> int:
        return sum(r for r, _ in self.per_frame.values())

    def table(self) -> str:
        """The confusion matrix as text (rows: label, columns: read)."""
        labels = sorted({a for a, _ in self.confusion})
        reads = sorted({b for _, b in self.confusion})
        lines = ["label \\ read".ljust(13) + "".join(r[:8].rjust(9) for r in reads)]
        for a in labels:
            lines.append(a.ljust(13) + "".join(str(self.confusion.get((a, b), 0) or ".").rjust(9) for b in reads))
        return "\n".join(lines)


def score_colors(model: ColorModel, data_dir: str | Path, include_uncertain: bool = False) -> ColorScore:
    """The model's colour at every labelled top face that shows (not occluded; uncertain ones only with
    include_uncertain). Faces of colours outside the model's classes (black, pink) are in the confusion
    and the readings, not in the per-frame figures."""
    confusion: Counter = Counter()
    per_frame: dict = {}
    readings = []
    images: dict = {}
    for face in read_labelled_faces(data_dir):
        if face.occluded or (face.uncertain and not include_uncertain):
            continue
        image = images.get(face.frame)
        if image is None:
            image = images[face.frame] = cv2.imread(str(Path(data_dir) / f"image_{face.frame}.png"), cv2.IMREAD_COLOR)
        reading = classify_face(model, image, face)
        confusion[(face.color, reading.name)] += 1
        readings.append((face, reading))
        if face.color not in model.classes:
            continue
        right, counted = per_frame.get(face.frame, [0, 0])
        per_frame[face.frame] = [right + int(reading.name == face.color), counted + 1]
    return ColorScore(confusion, per_frame, readings)
