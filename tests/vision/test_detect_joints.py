"""The arm is never a block, offline too (issue 17 item 4): `armlab detect --joints q1,... [--arm NAME]`
applies the live station's robot self-filter. On a real ROB 550 frame the RX200 stands in view near the
bottom centre in its sleep pose: without --joints a 'block' is reported on it, with the sleep joints
none is, and every other detection is unchanged. Bad --joints / --arm -> exit 2 naming the option
(on a synthetic board frame: checked without the data folder)."""

from __future__ import annotations

import json

import cv2
import pytest

from armlab.cli import main
from armlab.vision import calibrate_extrinsics
from rob550_dev import DEV, f21_intrinsics, needs_dev_frames, rob550_config

SLEEP_RAD = "0,-1.80,1.55,0.8,0"  # the RX200's sleep pose (DESIGN §4), where the course frames show it
FRAME = "blocks"


def _on_the_arm(block: dict) -> bool:
    """A detection standing on the arm: over the strip the folded arm covers (|x| < 80 mm, y < 150 mm,
    the base at the world origin) and higher than any cube on the board (> 60 mm)."""
    x, y, z = block["position_m"]
    return abs(x) < 0.08 and y < 0.15 and z > 0.06


@pytest.fixture(scope="module")
def frame_files(tmp_path_factory):
    """The frame's colour and depth paths and a calibration JSON made from its board tags."""
    if not DEV.is_dir():
        pytest.skip(f"the real ROB 550 development frames are not on this machine (looked in {DEV})")
    tmp = tmp_path_factory.mktemp("detect_joints")
    color, depth = DEV / f"image_{FRAME}.png", DEV / f"depth_{FRAME}.png"
    cal = calibrate_extrinsics(cv2.imread(str(color)), f21_intrinsics(), rob550_config(tmp),
                               depth_mm=cv2.imread(str(depth), cv2.IMREAD_UNCHANGED))
    cal_path = tmp / "calibration.json"
    cal.save(cal_path)
    return [str(color), "--depth", str(depth), "--calibration", str(cal_path)]


@pytest.fixture(scope="module")
def board_files(tmp_path_factory, board_frame, intrinsics, cfg):
    """A synthetic board frame (exact geometry, no arm), its depth and calibration: for the bad-input checks."""
    tmp = tmp_path_factory.mktemp("detect_joints_board")
    color, depth = board_frame
    cv2.imwrite(str(tmp / "color.png"), color)
    cv2.imwrite(str(tmp / "depth.png"), depth)
    calibrate_extrinsics(color, intrinsics, cfg, depth_mm=depth).save(tmp / "calibration.json")
    return [str(tmp / "color.png"), "--depth", str(tmp / "depth.png"), "--calibration", str(tmp / "calibration.json")]


def _detect(capsys, frame_files, *extra: str) -> list[dict]:
    assert main(["detect", *frame_files, "--all", *extra]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


@needs_dev_frames
def test_the_arm_in_a_real_frame_is_a_block_without_joints_and_none_with_them(capsys, frame_files):
    without = _detect(capsys, frame_files)
    on_arm = [b for b in without if _on_the_arm(b)]
    assert on_arm, f"expected the arm reported as a block without --joints: {without}"
    with_joints = _detect(capsys, frame_files, "--joints", SLEEP_RAD)
    assert not [b for b in with_joints if _on_the_arm(b)], with_joints
    # Nothing else changes: the filter takes the arm, not the cubes next to it (--all stamps the joints).
    assert all(b.pop("seen_arm_joints_rad") == pytest.approx([0.0, -1.8, 1.55, 0.8, 0.0]) for b in with_joints)
    # The same blocks, each where it was: the board plane is refitted without the arm's pixels, so
    # positions may move by a fraction of a millimetre, classes not at all.
    _assert_same_blocks(with_joints, [b for b in without if b not in on_arm])
    # The workcell's arm by name gives the same.
    _assert_same_blocks(_detect(capsys, frame_files, "--joints", SLEEP_RAD, "--arm", "rx200"), with_joints)


def _assert_same_blocks(found: list[dict], expected: list[dict], tolerance_m: float = 0.001) -> None:
    """Pairs every expected block with one found of the same class within tolerance_m; none left over."""
    classes = lambda b: (b["color"], b["size"], b["is_cube"], b["stack_level"])  # noqa: E731
    left = list(found)
    for block in expected:
        match = next((f for f in left if classes(f) == classes(block)
                      and max(abs(a - c) for a, c in zip(f["position_m"], block["position_m"])) <= tolerance_m), None)
        assert match is not None, f"{block} not found among {left}"
        left.remove(match)
    assert not left, f"extra blocks: {left}"


@pytest.mark.parametrize("args, says", [
    (["--joints", "0,-1.8,1.55"], "--joints: arm rx200 has 5 joints"),
    (["--joints", "0,nan,1.55,0.8,0"], "--joints: 'nan' is not a finite number"),
    (["--joints", "0,-1.8,inf,0.8,0"], "--joints: 'inf' is not a finite number"),
    (["--joints", "0,-1.8,elbow,0.8,0"], "--joints: 'elbow' is not a number"),
    (["--joints", ""], "--joints: '' is not a number"),
    (["--joints", "0,-3.0,1.55,0.8,0"], "--joints: joint 'shoulder'"),
    (["--arm", "rx200"], "--arm names the arm whose --joints are given"),
    (["--joints", SLEEP_RAD, "--arm", "no_such_arm"], "--arm no_such_arm"),
    (["--joints", SLEEP_RAD, "--arm", "ur3"], "--joints: arm ur3 has 6 joints"),
])
def test_bad_joints_or_arm_is_a_clear_error(capsys, board_files, args, says):
    assert main(["detect", *board_files, *args]) == 2
    out = capsys.readouterr()
    assert out.out == "" and says in out.err and out.err.startswith("error: "), out.err

