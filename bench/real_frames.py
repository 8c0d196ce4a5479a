"""Block detection on hand-labelled real frames (default: the ROB 550 development set in
../shared/data/rob550_dev): per frame, calibrate from the board tags with the frame's intrinsics,
detect blocks with the shipped defaults, match them to the labelled cubes by pixel distance and print
labelled cubes, found as cubes, colour / size / stack level right, extras, distractors called cubes,
centre error (px, mm), height error against the labels' depth heights, the calibration's reprojection
error, the depth camera's offset and tilt against the tags' plane, tags found and false tags.

    .venv/bin/python bench/real_frames.py [--data DIR] [--board rob550] [--verbose]

DIR holds image_<name>.png, depth_<name>.png (16-bit mm, aligned) and image_<name>.labels.json, and
the intrinsics: intrinsics.json (K, dist, image_size: one camera for every frame), or a
calibration_*.json with K_from_camera_info / D_from_camera_info_plumb_bob naming its station's frames
in "station" (other frames use the same K, marked "assumed"), else config/cameras/sim_l515.yaml.
Targets (issue 17): recall, colour, size and precision >= 98 %, every frame calibrated, 0 false tags.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from armlab.config import config_dir  # noqa: E402
from armlab.devices.camera import Intrinsics  # noqa: E402
from armlab.vision import calibrate_extrinsics, detect_tags, load_perception_config  # noqa: E402
from armlab.vision.pipeline import PerceptionPipeline  # noqa: E402
from armlab.vision.real_eval import Detection, FrameScore, load_labels, score_frame  # noqa: E402
from armlab.vision.rgbd_files import read_color, read_depth  # noqa: E402
from armlab.workcell import load_workcell  # noqa: E402

DEFAULT_DATA = REPO.parent / "shared" / "data" / "rob550_dev"


def perception_config(board: str | None):
    """The shipped perception defaults on the default workcell, its board tags replaced by
    config/boards/<board>.yaml when given (the course's frames: rob550, tagStandard41h12)."""
    if board is None:
        return load_perception_config()
    data = yaml.safe_load((config_dir() / "workcells" / "rx200_armlab.yaml").read_text())
    data["board_tags"] = board
    path = Path(tempfile.mkdtemp(prefix="real_frames_")) / f"rx200_{board}.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_perception_config(workcell=load_workcell(str(path)))


def _intrinsics(K, dist, width: int, height: int) -> Intrinsics:
    K = np.asarray(K, dtype=float)
    return Intrinsics(int(width), int(height), float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]),
                      tuple(float(x) for x in np.ravel(dist)))


def intrinsics_for(data: Path, name: str, width: int, height: int) -> tuple[Intrinsics, str]:
    """(intrinsics, where they came from) for frame `name` of the folder (see the module's docstring)."""
    single = data / "intrinsics.json"
    if single.exists():
        d = json.loads(single.read_text())
        w, h = d.get("image_size", (width, height))
        return _intrinsics(d["K"], d.get("dist", [0.0] * 5), w, h), single.name
    for path in sorted(data.glob("calibration_*.json")):
        d = json.loads(path.read_text())
        if "K_from_camera_info" not in d:
            continue
        intr = _intrinsics(d["K_from_camera_info"], d.get("D_from_camera_info_plumb_bob", [0.0] * 5), width, height)
        station = str(d.get("station", ""))
        return (intr, f"{path.name} camera_info") if name in station else (intr, f"assumed: {path.name}'s K (another station)")
    from armlab.cli.vision_cmd import load_intrinsics

    return load_intrinsics(None), "assumed: config/cameras/sim_l515.yaml"


def _fmt(values: list[float], scale: float = 1.0, digits: int = 1) -> str:
    if not values:
        return "-"
    a = np.abs(np.asarray(values)) * scale
    return f"{a.mean():.{digits}f}/{a.max():.{digits}f}"


def _pct(num: int, den: int) -> str:
    return f"{100.0 * num / den:.1f} %" if den else "-"


def run_frame(data: Path, labels_path: Path, cfg, verbose: bool) -> tuple[str, FrameScore, dict]:
    name = labels_path.name[len("image_"):-len(".labels.json")]
    labels = load_labels(labels_path)
    color = read_color(data / f"image_{name}.png")
    height, width = color.shape[:2]
    depth = read_depth(data / f"depth_{name}.png", (width, height))
    intr, source = intrinsics_for(data, name, width, height)
    tags = detect_tags(color, cfg)
    found_tags = [(t.id, float(t.center_px[0]), float(t.center_px[1])) for t in tags]
    info = {"name": name, "intrinsics": source, "tags": sorted(t[0] for t in found_tags),
            "false_tags": labels.false_tags(found_tags)}
    t0 = time.perf_counter()
    try:
        cal = calibrate_extrinsics(color, intr, cfg, depth_mm=depth, tags=tags)
    except ValueError as error:
        info["error"] = str(error)
        s = FrameScore()
        s.labelled = sum(1 for c in labels.cubes if not (c.occluded or c.uncertain or c.other))
        s.misses = [f"({c.u:.0f},{c.v:.0f}) {c.color} {c.size}" for c in labels.cubes if not (c.occluded or c.uncertain or c.other)]
        return name, s, info
    blocks = PerceptionPipeline(cfg).process(color, depth, cal, layers=None).blocks
    info["ms"] = (time.perf_counter() - t0) * 1000
    info["reprojection_px"] = cal.reprojection_error_px
    info["depth_offset_mm"] = getattr(cal, "depth_offset_m", None)
    info["depth_tilt_deg"] = getattr(cal, "depth_tilt_deg", None)
    if info["depth_offset_mm"] is not None:
        info["depth_offset_mm"] *= 1000.0
    cubes = [b for b in blocks if b.is_cube]
    detections = [Detection(float(b.center_px[0]), float(b.center_px[1]), b.color, b.size, b.stack_level, b.height_m * 1000.0,
                            (float(b.position_m[0]) * 1000.0, float(b.position_m[1]) * 1000.0)) for b in cubes]
    fx = float(cal.K[0, 0])
    camera_height_m = float(cal.T_world_camera[2, 3])
    mm_per_px = camera_height_m / fx * 1000.0
    large_px = cfg.blocks.large_size_m * 1000.0 / mm_per_px
    score = score_frame(labels, detections, radius_px=0.75 * large_px, mm_per_px=mm_per_px)
    info["non_cubes"] = len(blocks) - len(cubes)
    if verbose:
        for b in blocks:
            print(f"      {'cube ' if b.is_cube else 'other'} ({b.center_px[0]:4.0f},{b.center_px[1]:4.0f}) {b.color:7s} {b.size:5s} "
                  f"L{b.stack_level} h {b.height_m * 1000:5.1f} mm side {b.side_m * 1000:4.1f} mm{' occluded' if b.occluded else ''}")
    return name, score, info


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(DEFAULT_DATA), help="folder of labelled frames (default ../shared/data/rob550_dev)")
    parser.add_argument("--board", default="rob550", help="config/boards/<name>.yaml for the board tags (default rob550)")
    parser.add_argument("--verbose", action="store_true", help="list every detection, miss and wrong reading")
    args = parser.parse_args(argv)
    data = Path(args.data)
    label_files = sorted(data.glob("image_*.labels.json"))
    if not label_files:
        print(f"error: no image_*.labels.json in {data}", file=sys.stderr)
        return 2
    cfg = perception_config(args.board)
    head = (f"{'frame':>14} {'lab':>4} {'found':>5} {'col':>4} {'size':>4} {'lvl':>4} {'extra':>5} {'distr':>5} {'unc f/l':>7} "
            f"{'oth f/l':>7} {'hid':>3} {'ctr px':>9} {'ctr mm':>9} {'h err mm':>9} {'reproj':>6} {'d off mm':>8} {'tilt':>5} "
            f"{'tags':>9} {'false':>5} {'ms':>5}")
    print(head)
    total = FrameScore()
    calibrated, false_tags = 0, 0
    for path in label_files:
        name, s, info = run_frame(data, path, cfg, args.verbose)
        total.add(s)
        false_tags += len(info["false_tags"])
        if "error" in info:
            print(f"{name:>14} {s.labelled:4d}  NOT CALIBRATED: {info['error']}  [{info['intrinsics']}]")
            continue
        calibrated += 1
        off = "-" if info["depth_offset_mm"] is None else f"{info['depth_offset_mm']:+.1f}"
        tilt = "-" if info["depth_tilt_deg"] is None else f"{info['depth_tilt_deg']:.2f}"
        print(f"{name:>14} {s.labelled:4d} {s.found:5d} {s.color_right:4d} {s.size_right:4d} {s.level_right:4d} {s.extras:5d} "
              f"{s.distractors_called_cubes:5d} {s.uncertain_found:3d}/{s.uncertain_labelled:<3d} {s.other_found:3d}/{s.other_labelled:<3d} "
              f"{s.hidden_members:3d} {_fmt(s.centre_errors_px):>9} {_fmt(s.centre_errors_mm):>9} {_fmt(s.height_errors_mm):>9} "
              f"{info['reprojection_px']:6.2f} {off:>8} {tilt:>5} {','.join(map(str, info['tags'])):>9} {len(info['false_tags']):5d} "
              f"{info['ms']:5.0f}")
        if info["intrinsics"].startswith("assumed"):
            print(f"{'':>14}   intrinsics {info['intrinsics']}")
        if args.verbose:
            for line in s.misses:
                print(f"{'':>14}   miss {line}")
            for line in s.wrong:
                print(f"{'':>14}   wrong {line}")
    reported = total.found + total.extras + total.distractors_called_cubes
    print(f"{'total':>14} {total.labelled:4d} {total.found:5d} {total.color_right:4d} {total.size_right:4d} {total.level_right:4d} "
          f"{total.extras:5d} {total.distractors_called_cubes:5d} {total.uncertain_found:3d}/{total.uncertain_labelled:<3d} "
          f"{total.other_found:3d}/{total.other_labelled:<3d} {total.hidden_members:3d} {_fmt(total.centre_errors_px):>9} "
          f"{_fmt(total.centre_errors_mm):>9} {_fmt(total.height_errors_mm):>9}")
    print(f"recall {_pct(total.found, total.labelled)}, colour right {_pct(total.color_right, total.found)}, "
          f"size right {_pct(total.size_right, total.found)}, stack level right {_pct(total.level_right, total.found)}, "
          f"precision {_pct(total.found, reported)} (extras + distractors called cubes: {total.extras + total.distractors_called_cubes}), "
          f"calibrated {calibrated}/{len(label_files)} frames, false tags {false_tags}")
    print("columns: lab = sure labelled cubes (visible, not uncertain, one of the classes); unc/oth f/l = uncertain / other-colour "
          "cubes found/labelled (not in the targets); hid = hidden lower stack members (not expected: stack tops are reported); "
          "ctr and h err: mean/max; h err = detected top minus the label's depth height; d off = depth camera's board plane "
          "minus the tags' plane along the board normal, tilt = angle between them")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
