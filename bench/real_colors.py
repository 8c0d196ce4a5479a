"""Block colour accuracy on hand-labelled real frames, read at each labelled cube's top-face centre with the
shipped colour model (config/vision.yaml color_model; armlab/vision/colors.py), independent of block
detection: per frame and in total, the confusion matrix, the cubes outside the six colours (black, pink:
'unknown' is the right answer for them with the defaults), the uncertain labels apart, and the same
frames under other light (the whole image scaled per channel: dim, bright, warm, cool; what the board
normalisation must absorb).

    .venv/bin/python bench/real_colors.py [--data DIR] [--no-relight]

DIR holds image_<name>.png and image_<name>.labels.json (default ../shared/data/rob550_dev).
Target (issue 17): colour right >= 98 %.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from armlab.vision import load_perception_config  # noqa: E402
from armlab.vision.colors import ColorModel  # noqa: E402
from armlab.vision.colors_eval import read_labelled_faces, score_colors  # noqa: E402

DEFAULT_DATA = REPO.parent / "shared" / "data" / "rob550_dev"
LIGHTS = {"dim x0.5": (0.5, 0.5, 0.5), "bright x1.3": (1.3, 1.3, 1.3), "warm": (0.75, 1.0, 1.2), "cool": (1.2, 1.0, 0.8)}


def report(model: ColorModel, data: Path, title: str, tables: bool = True) -> float:
    score = score_colors(model, data)
    total = 100.0 * score.right / max(1, score.counted)
    print(f"\n{title}: {score.right}/{score.counted} right ({total:.1f} %)")
    for frame, (right, n) in sorted(score.per_frame.items()):
        print(f"  {frame:14s} {right:3d}/{n:<3d} {100.0 * right / n:5.1f} %")
    if tables:
        print(score.table())
        for face, reading in score.readings:
            wrong = reading.name != face.color if face.color in model.classes else reading.name != "unknown"
            if wrong or face.extra:
                print(f"  {face.frame} {face.color} {face.size} at ({face.u}, {face.v}): read {reading.name} "
                      f"(nearest {reading.nearest} at {reading.distance:.1f}; Lab {reading.measured_lab})")
        uncertain = score_colors(model, data, include_uncertain=True)
        print(f"  with the uncertain labels too: {uncertain.right}/{uncertain.counted}")
    return total


def relit_copy(data: Path, gain_bgr, folder: Path) -> Path:
    """The folder's labelled frames with every pixel scaled per channel (8-bit clipping as a camera would)."""
    for face_file in sorted(data.glob("image_*.labels.json")):
        name = face_file.name[: -len(".labels.json")]
        image = cv2.imread(str(data / f"{name}.png"))
        cv2.imwrite(str(folder / f"{name}.png"), np.clip(image * np.asarray(gain_bgr), 0, 255).astype(np.uint8))
        (folder / face_file.name).write_text(face_file.read_text())
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--no-relight", action="store_true")
    args = parser.parse_args()
    if not read_labelled_faces(args.data):
        sys.exit(f"no labelled frames (image_*.labels.json) in {args.data}")
    model = ColorModel.from_config(load_perception_config())
    report(model, args.data, "shipped colour model at the labelled centres")
    if not args.no_relight:
        for light, gain in LIGHTS.items():
            with tempfile.TemporaryDirectory() as folder:
                report(model, relit_copy(args.data, gain, Path(folder)), f"under other light ({light}, BGR gains {gain})", tables=False)


if __name__ == "__main__":
    main()
