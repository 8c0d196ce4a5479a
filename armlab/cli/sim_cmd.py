"""`armlab render`: write one simulated camera frame (colour PNG, 16-bit depth PNG in mm) and the
ground truth as JSON, for a competition event/level, a scene file or a random layout."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("render", help="render one simulated camera frame and its ground truth")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--event", help="competition event: pick_sort, pick_stack, line_up, stack_high, to_the_sky")
    source.add_argument("--scene", type=Path, help="scene file (JSON or YAML): {\"objects\": [...]} as in the truth")
    parser.add_argument("--level", type=int, default=1, help="event level (default 1)")
    parser.add_argument("--seed", type=int, default=0, help="seed for the layout, the camera bump and the noise")
    parser.add_argument("--out", type=Path, required=True, help="colour image path (PNG)")
    parser.add_argument("--depth", type=Path, help="depth image path (16-bit PNG, millimetres)")
    parser.add_argument("--truth", type=Path, help="ground-truth JSON path")
    parser.add_argument("--no-noise", action="store_true", help="turn colour and depth noise off")
    parser.add_argument("--no-pose-error", action="store_true", help="mount the camera exactly at its nominal pose")
    parser.add_argument("--realism", choices=("real", "camera", "ideal"), default=None,
                        help="real: a real L515's imperfections, shadows and clutter; ideal: exact (default: config/sim.yaml)")
    parser.add_argument("--settle", type=float, default=0.3, help="seconds of physics before the frame (default 0.3)")
    parser.set_defaults(func=run_render)

    scene_parser = subparsers.add_parser("scene", help="print a generated scene as JSON (the scene-file format)")
    scene_parser.add_argument("--event", help="competition event (default: a random layout from the seed)")
    scene_parser.add_argument("--level", type=int, default=1)
    scene_parser.add_argument("--seed", type=int, default=0)
    scene_parser.add_argument("--aruco", action="store_true", help="ArUco tags on yellow/red/blue block tops")
    scene_parser.add_argument("--out", type=Path, help="write to this file instead of stdout")
    scene_parser.set_defaults(func=run_scene, scene=None)


def load_scene(args: argparse.Namespace):
    """The scene chosen on the command line (event/level, file, or a random layout from the seed)."""
    from armlab.config import read_config_file
    from armlab.scene import Scene, generate_scene
    from armlab.scene.random_layout import random_scene

    if args.scene is not None:
        return Scene.from_dict(read_config_file(args.scene))
    if args.event is not None:
        return generate_scene(args.event, level=args.level, seed=args.seed)
    return random_scene(seed=args.seed)


def run_render(args: argparse.Namespace) -> int:
    import os
    import sys

    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.errors import ConfigError

    try:
        scene = load_scene(args)
    except (ValueError, ConfigError) as error:
        print(f"armlab render: {error}", file=sys.stderr)
        return 2
    if not (0.0 <= args.settle <= 60.0):
        print("armlab render: --settle must be in [0, 60] s", file=sys.stderr)
        return 2
    config = SimWorkcellConfig(
        realtime=False,
        seed=args.seed,
        camera_pose_error=not args.no_pose_error,
        color_noise=not args.no_noise,
        depth_noise=not args.no_noise,
        realism=args.realism,
    )
    with SimWorkcell(config, scene=scene) as cell:
        cell.step(args.settle)
        frame = cell.render()
        truth = cell.truth()
    for path in (args.out, args.depth, args.truth):
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(args.out), frame.color_bgr):
        print(f"armlab render: cannot write {args.out}", file=sys.stderr)
        return 1
    if args.depth is not None and not cv2.imwrite(str(args.depth), frame.depth_mm):
        print(f"armlab render: cannot write {args.depth}", file=sys.stderr)
        return 1
    if args.truth is not None:
        args.truth.write_text(json.dumps(truth, indent=2))
    print(json.dumps({"color": str(args.out), "depth": str(args.depth) if args.depth else None,
                      "truth": str(args.truth) if args.truth else None, "objects": len(truth["objects"])}))
    return 0


def run_scene(args: argparse.Namespace) -> int:
    import sys

    from armlab.scene.aruco_tops import with_aruco_tops

    try:
        scene = load_scene(args)
    except ValueError as error:
        print(f"armlab scene: {error}", file=sys.stderr)
        return 2
    if args.aruco:
        scene = with_aruco_tops(scene)
    text = json.dumps(scene.to_dict(), indent=2)
    if args.out is not None:
        args.out.write_text(text)
    else:
        print(text)
    return 0
