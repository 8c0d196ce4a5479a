"""Measure the colour model's class references (config/vision.yaml color_model.references): the median
board-normalised CIELAB of each class's labelled top faces, per real station of the development set
(../shared/data/rob550_dev: the F21 course station's six frames and room 204's two), and of the
simulation's rendered cubes (seeded scenes, top-face centres from the simulator's truth). Faces
labelled uncertain or occluded are left out. Prints the YAML to paste, and each station's figures
when the model is built WITHOUT that station's references (leave one station out: what a new
station with other light can expect from the shipped defaults).

    MUJOCO_GL=egl .venv/bin/python bench/color_references.py [--data DIR] [--sim-scenes 4]
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import defaultdict
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import cv2  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from armlab.vision import load_perception_config  # noqa: E402
from armlab.vision.colors import ColorModel, board_region_mask, measure_at  # noqa: E402
from armlab.vision.colors_eval import measure_face, read_labelled_faces, score_colors  # noqa: E402

DEFAULT_DATA = REPO.parent / "shared" / "data" / "rob550_dev"


def station_of(frame: str) -> str:
    """The development set's two stations: room 204's frames and the F21 course station's."""
    return "room204" if frame.startswith("204") else "f21"


def real_samples(model: ColorModel, data: Path) -> dict[str, dict[str, list]]:
    """station -> class -> [CIELAB] of the labelled, certain, visible faces of the model's classes."""
    out: dict = defaultdict(lambda: defaultdict(list))
    images: dict = {}
    for face in read_labelled_faces(data):
        if face.occluded or face.uncertain or face.extra or face.color not in model.classes:
            continue
        image = images.setdefault(face.frame, cv2.imread(str(data / f"image_{face.frame}.png")))
        out[station_of(face.frame)][face.color].append(measure_face(model, image, face))
    return out


def sim_samples(model: ColorModel, cfg, scenes: int) -> dict[str, list]:
    """class -> [CIELAB] of resting cube tops in seeded line_up scenes (every colour, both sizes)."""
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.scene import generate_scene
    from armlab.vision.evaluate import expected_tops
    from armlab.vision.geometry import project_points

    out: dict = defaultdict(list)
    for seed in range(scenes):
        cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=seed, camera_pose_error=True))
        cell.start()
        try:
            cell.set_scene(generate_scene("line_up", level=1 + seed % 2, seed=seed))
            cell.step(0.5)
            frame, truth = cell.render(), cell.truth()
        finally:
            cell.close()
        T = np.asarray(truth["camera"]["T_world_camera"])
        K = np.asarray(truth["camera"]["K"])
        for top in expected_tops(truth):
            if top.type != "block" or not top.resting:
                continue
            u, v = project_points(T, K, np.zeros(5), top.top_center_m.reshape(1, 3))[0]
            side = (0.038 if top.size == "large" else 0.025) * K[0, 0] / (T[2, 3] - top.top_center_m[2])
            board = board_region_mask(frame.color_bgr.shape[:2], T, K, np.zeros(5), cfg.board.x_range_m, cfg.board.y_range_m)
            out[top.color].append(measure_at(model, frame.color_bgr, (u, v), side, board))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--sim-scenes", type=int, default=4)
    args = parser.parse_args()
    cfg = load_perception_config()
    shipped = ColorModel.from_config(cfg)
    real = real_samples(shipped, args.data)
    sim = sim_samples(shipped, cfg, args.sim_scenes)
    refs: dict[str, dict[str, np.ndarray]] = {station: {c: np.median(v, axis=0) for c, v in per.items()} for station, per in real.items()}
    refs["sim"] = {c: np.median(v, axis=0) for c, v in sim.items()}
    print("color_model.references (median L, a, b; board-normalised):")
    for c in shipped.classes:
        parts = []
        for source in ("f21", "room204", "sim"):
            if c in refs.get(source, {}):
                n = len(real[source][c]) if source != "sim" else len(sim[c])
                parts.append(f"[{', '.join(f'{x:.1f}' for x in refs[source][c])}]  # {source}, {n} faces")
        print(f"    {c}:\n" + "".join(f"      - {p}\n" for p in parts), end="")
    print("\nshipped model at the labelled centres (all frames, certain faces):")
    score = score_colors(shipped, args.data)
    print(f"  {score.right}/{score.counted} right ({100.0 * score.right / max(1, score.counted):.1f} %)")
    for station in sorted(real):
        others = {c: tuple(tuple(float(x) for x in refs[s][c]) for s in refs if s != station and c in refs[s]) for c in shipped.classes}
        held_out = ColorModel(others, shipped.board_reflectance, shipped.k_lightness, shipped.k_chroma, shipped.max_distance,
                              shipped.min_chroma, shipped.names)
        s = score_colors(held_out, args.data)
        frames = {f: rc for f, rc in s.per_frame.items() if station_of(f) == station}
        right, counted = sum(r for r, _ in frames.values()), sum(n for _, n in frames.values())
        print(f"  leave {station} out: {station}'s faces {right}/{counted} right ({100.0 * right / max(1, counted):.1f} %)")
        for face, reading in s.readings:
            if station_of(face.frame) == station and reading.name != (face.color if face.color in shipped.classes else "unknown"):
                print(f"    {face.frame} {face.color} {face.size} at ({face.u}, {face.v}) read {reading.name} "
                      f"(d {reading.distance:.1f}, Lab {reading.measured_lab})")


if __name__ == "__main__":
    main()
