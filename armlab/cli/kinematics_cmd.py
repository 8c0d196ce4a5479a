"""`armlab fk ARM Q1 ... Qn` and `armlab ik ARM X Y Z [--pitch RAD] [--yaw RAD]`: JSON on stdout.

World frame, metres and radians. Bad input (NaN, wrong count, unknown arm) and unreachable targets
exit with status 2 and {"error": "..."}, so scripts can tell them from a crash.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from armlab.errors import ConfigError


class _InputError(ValueError):
    """Bad command-line input (reported as JSON with exit status 2)."""


def _numbers(texts: list[str], what: str) -> list[float]:
    values = []
    for text in texts:
        try:
            value = float(text)
        except ValueError:
            raise _InputError(f"{what}: '{text}' is not a number") from None
        if not math.isfinite(value):
            raise _InputError(f"{what}: '{text}' is not a finite number")
        values.append(value)
    return values


def _fail(message: str) -> int:
    print(json.dumps({"error": message}))
    return 2


def _run_fk(args: argparse.Namespace) -> int:
    from armlab.kinematics import load_arm
    from armlab.kinematics.screws import rpy_from_rotation

    try:
        arm = load_arm(args.arm)
        q = _numbers(args.q, "joint angles")
        if len(q) != arm.dof:
            raise _InputError(f"joint angles: {arm.name} has {arm.dof} joints ({', '.join(arm.joint_names)}), got {len(q)} values")
        if not arm.within_limits(q):
            raise _InputError(f"joint angles: {q} is outside the joint limits of {arm.name}")
        pose = arm.fk(q)
    except (ConfigError, ValueError) as error:
        return _fail(str(error))
    print(json.dumps({
        "position_m": pose[:3, 3].tolist(),
        "rpy_rad": rpy_from_rotation(pose[:3, :3]).tolist(),
        "matrix": pose.tolist(),
    }))  # fmt: skip
    return 0


def _run_ik(args: argparse.Namespace) -> int:
    from armlab.kinematics import Unreachable, load_arm

    try:
        arm = load_arm(args.arm)
        position = _numbers(args.xyz, "target position")
        if len(position) != 3:
            raise _InputError(f"target position: expected X Y Z (3 numbers), got {len(position)}")
        pitch = None if args.pitch is None else _numbers([args.pitch], "--pitch")[0]
        yaw = None if args.yaw is None else _numbers([args.yaw], "--yaw")[0]
        seed = None if args.seed is None else _numbers(args.seed, "--seed")
        if seed is not None and len(seed) != arm.dof:
            raise _InputError(f"--seed: {arm.name} has {arm.dof} joints, got {len(seed)} values")
        q, pitch_used = arm.ik_with_pitch(position, pitch=pitch, yaw=yaw, q_seed=seed)
    except Unreachable as error:
        return _fail(f"unreachable: {error}")
    except (ConfigError, ValueError) as error:
        return _fail(str(error))
    print(json.dumps({"q_rad": q.tolist(), "pitch_rad": pitch_used}))
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the `fk` and `ik` subcommands."""
    fk = subparsers.add_parser("fk", help="forward kinematics: gripper pose (world frame) as JSON")
    fk.add_argument("arm", help="arm name in config/arms (e.g. rx200, ur3) or a path to an arm file")
    fk.add_argument("q", nargs="*", metavar="Q", help="joint angles in radians, one per joint")
    fk.set_defaults(func=_run_fk)

    ik = subparsers.add_parser("ik", help="inverse kinematics: joint angles reaching X Y Z (world, metres)")
    ik.add_argument("arm", help="arm name in config/arms (e.g. rx200, ur3) or a path to an arm file")
    ik.add_argument("xyz", nargs="*", metavar="X Y Z", help="gripper-point target in the world frame (m)")
    ik.add_argument("--pitch", metavar="RAD", help="approach below horizontal (pi/2 = straight down); default: steepest reachable")
    ik.add_argument("--yaw", metavar="RAD", help="block yaw in the world frame; aligns the fingers with its faces")
    ik.add_argument("--seed", nargs="+", metavar="Q", help="joint vector to stay close to (default: home)")
    ik.set_defaults(func=_run_ik)


if __name__ == "__main__":  # pragma: no cover
    parser = argparse.ArgumentParser(prog="armlab")
    register(parser.add_subparsers(dest="command", required=True))
    parsed = parser.parse_args()
    sys.exit(parsed.func(parsed))
