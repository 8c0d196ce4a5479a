"""`armlab tags | calibrate-intrinsics | calibrate-extrinsics | calibrate-points | detect`: perception on image files,
for offline use and scripts. Output is JSON on stdout; errors are one sentence on stderr, exit 2."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    tags = subparsers.add_parser("tags", help="detect fiducial tags in an image (JSON list of id + corners)")
    tags.add_argument("image")
    tags.add_argument("--family", "--dict", dest="dict", default=None,
                      help="tag36h11 | tagStandard41h12 (AprilTag library) | DICT_... (OpenCV ArUco); default: the workcell's board tags")
    tags.add_argument("--corners", choices=("opencv", "apriltag"), default="opencv",
                      help="corner convention: opencv (TL, TR, BR, BL, pixel centres at integers; the station's) or "
                           "apriltag (the AprilTag library's: counter-clockwise from bottom-left, pixel centres at +0.5)")
    tags.set_defaults(func=run_tags)

    intr = subparsers.add_parser("calibrate-intrinsics", help="camera intrinsics from checkerboard images")
    intr.add_argument("images", nargs="+")
    intr.add_argument("--pattern", default="9x6", help="inner corners, columns x rows (default 9x6)")
    intr.add_argument("--square", type=float, default=0.025, help="square size in metres (default 0.025)")
    intr.add_argument("--free-aspect", action="store_true", help="do not fix fx/fy (OpenCV's CALIB_FIX_ASPECT_RATIO is the default)")
    intr.set_defaults(func=run_calibrate_intrinsics)

    extr = subparsers.add_parser("calibrate-extrinsics", help="camera pose from the board tags (and depth cross-check)")
    extr.add_argument("color")
    extr.add_argument("--depth", default=None, help="16-bit PNG depth in mm, aligned to colour")
    extr.add_argument("--out", required=True, help="calibration JSON to write")
    extr.add_argument("--intrinsics", default=None, help="camera YAML (config/cameras format) or intrinsics JSON (default sim_l515)")
    extr.set_defaults(func=run_calibrate_extrinsics)

    pts = subparsers.add_parser("calibrate-points", help="camera pose from >= 4 clicked pixels with known world points (no tags)")
    pts.add_argument("--point", action="append", default=[], metavar="U,V,X,Y[,Z]",
                     help="a clicked pixel (u, v) and its world point in metres (z = 0 if left out); repeat >= 4 times")
    pts.add_argument("--depth", default=None, help="16-bit PNG depth in mm, aligned to colour (cross-check)")
    pts.add_argument("--out", required=True, help="calibration JSON to write")
    pts.add_argument("--intrinsics", default=None, help="camera YAML (config/cameras format) or intrinsics JSON (default sim_l515)")
    pts.set_defaults(func=run_calibrate_points)

    det = subparsers.add_parser("detect", help="blocks in a colour + depth frame (JSON)")
    det.add_argument("color")
    det.add_argument("--depth", required=True, help="16-bit PNG depth in mm, aligned to colour")
    det.add_argument("--calibration", required=True, help="calibration JSON from calibrate-extrinsics")
    det.add_argument("--all", action="store_true", help="include non-cubes (distractors) and every field")
    det.add_argument("--joints", default=None, metavar="Q1,Q2,...",
                     help="the arm's joints (rad, comma-separated) when the frame was taken: the robot self-filter "
                          "the live station uses then keeps the arm (and a block it holds) from being reported")
    det.add_argument("--arm", default=None,
                     help="the arm of --joints: config/arms/<name>.yaml or a path (default: the workcell's arm at its base pose)")
    det.set_defaults(func=run_detect)


def _fail(message: str) -> int:
    print(f"error: {message}", file=sys.stderr)
    return 2


def _read_color(path: str):
    import cv2

    image = cv2.imread(path, cv2.IMREAD_COLOR)
    if image is None:
        raise ValueError(f"cannot read image {path}")
    return image


def _read_depth(path: str):
    import cv2
    import numpy as np

    depth = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if depth is None:
        raise ValueError(f"cannot read depth image {path}")
    if depth.ndim != 2 or depth.dtype != np.uint16:
        raise ValueError(f"depth image {path} must be single-channel 16-bit (mm), got {depth.dtype} {depth.shape}")
    return depth


def load_intrinsics(path: str | None):
    """Intrinsics from a config/cameras YAML (default sim_l515) or a JSON with K, dist and image_size."""
    from armlab.config import read_config_file, resolve_config_path
    from armlab.devices.camera import Intrinsics

    source = resolve_config_path(path or "sim_l515", "cameras")
    data = read_config_file(source)
    if "intrinsics" not in data:  # an intrinsics file (K, dist, image_size; ROS camera_info): the recorded camera reads the same
        from armlab.devices.recorded.intrinsics_file import read_intrinsics_file

        return read_intrinsics_file(source)[0]
    try:
        k = data["intrinsics"]
        return Intrinsics(int(data["width"]), int(data["height"]), float(k["fx"]), float(k["fy"]), float(k["cx"]), float(k["cy"]),
                          tuple(float(x) for x in k.get("dist", [0.0] * 5)))
    except (KeyError, TypeError, ValueError, IndexError) as error:
        raise ValueError(f"{source}: no usable intrinsics ({error})") from error


def run_tags(args: argparse.Namespace) -> int:
    from armlab.vision import detect_tags, load_perception_config

    try:
        tags = detect_tags(_read_color(args.image), load_perception_config(), dictionary=args.dict)
    except ValueError as error:
        return _fail(str(error))
    corners = (lambda t: t.corners_apriltag_px()) if args.corners == "apriltag" else (lambda t: t.corners_px)
    print(json.dumps([{"id": t.id, "corners_px": corners(t).round(3).tolist(), "hamming": t.hamming,
                       "decision_margin": None if t.decision_margin is None else round(t.decision_margin, 2)} for t in tags]))
    return 0


def run_calibrate_intrinsics(args: argparse.Namespace) -> int:
    from armlab.vision.intrinsics import calibrate_intrinsics, parse_pattern

    try:
        result = calibrate_intrinsics(args.images, parse_pattern(args.pattern), args.square, fix_aspect_ratio=not args.free_aspect)
    except ValueError as error:
        return _fail(str(error))
    print(json.dumps(result.to_dict()))
    return 0


def run_calibrate_extrinsics(args: argparse.Namespace) -> int:
    from armlab.vision import calibrate_extrinsics, load_perception_config

    try:
        color = _read_color(args.color)
        depth = _read_depth(args.depth) if args.depth else None
        cal = calibrate_extrinsics(color, load_intrinsics(args.intrinsics), load_perception_config(), depth_mm=depth)
    except ValueError as error:
        return _fail(str(error))
    cal.save(Path(args.out))
    print(json.dumps(cal.to_dict()))
    return 0


def run_calibrate_points(args: argparse.Namespace) -> int:
    from armlab.vision import load_perception_config
    from armlab.vision.click_calibration import calibrate_from_points

    try:
        rows = [[float(v) for v in point.split(",")] for point in args.point]
        bad = [point for point, row in zip(args.point, rows) if len(row) not in (4, 5)]
        if bad:
            raise ValueError(f"--point {bad[0]!r}: expected U,V,X,Y or U,V,X,Y,Z")
        world = [row[2:] + [0.0] * (5 - len(row)) for row in rows]
        depth = _read_depth(args.depth) if args.depth else None
        cal, report = calibrate_from_points([row[:2] for row in rows], world, load_intrinsics(args.intrinsics),
                                            load_perception_config(), depth_mm=depth)
    except ValueError as error:
        return _fail(str(error))
    cal.save(Path(args.out))
    print(json.dumps({"calibration": cal.to_dict(), "fit": report}))
    return 0


def parse_joints(text: str, model):
    """--joints 'q1,q2,...' (radians) for the arm `model`: ValueError naming the option when a value is
    not a finite number, the count is not the arm's, or a joint is outside its limits."""
    import numpy as np

    from armlab.station.checks import checked_joints

    values = []
    for item in text.split(","):
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"--joints: {item.strip()!r} is not a number (expected radians, comma-separated)") from None
        if not np.isfinite(value):
            raise ValueError(f"--joints: {item.strip()!r} is not a finite number")
        values.append(value)
    if len(values) != model.dof:
        raise ValueError(f"--joints: arm {model.name} has {model.dof} joints ({', '.join(model.joint_names)}), got {len(values)} values")
    try:
        return checked_joints(model, values)
    except ValueError as error:
        raise ValueError(f"--joints: {error}") from None


def detect_arm_model(name: str | None, workcell: str):
    """The arm for --joints: the workcell's arm at its base pose, or config/arms/<name>.yaml (or a path)
    at its own; ValueError naming --arm when it cannot be loaded."""
    from armlab.kinematics import load_arm
    from armlab.workcell import load_workcell, load_workcell_arm

    cell = load_workcell(workcell)
    try:
        return load_workcell_arm(cell) if name is None or name == cell.arm else load_arm(name)
    except (ValueError, OSError) as error:
        raise ValueError(f"--arm {name}: {error}") from None


def run_detect(args: argparse.Namespace) -> int:
    from armlab.vision import Calibration, load_perception_config
    from armlab.vision.pipeline import PerceptionPipeline

    try:
        if args.arm is not None and args.joints is None:
            raise ValueError("--arm names the arm whose --joints are given: give --joints too")
        cfg = load_perception_config()
        model = detect_arm_model(args.arm, cfg.workcell) if args.joints is not None else None
        joints = parse_joints(args.joints, model) if model is not None else None
        cal = Calibration.load(args.calibration)
        color, depth = _read_color(args.color), _read_depth(args.depth)
        # The live station's pass: with joints, the self-filter's robot mask is kept out of block detection.
        blocks = PerceptionPipeline(cfg, model).process(color, depth, cal, layers=None, arm_joints_rad=joints).blocks
    except ValueError as error:
        return _fail(str(error))
    keys = ("color", "size", "position_m", "yaw_rad", "stack_level")
    out = [b.to_dict() if args.all else {k: b.to_dict()[k] for k in keys} for b in blocks if args.all or b.is_cube]
    print(json.dumps(out))
    return 0
