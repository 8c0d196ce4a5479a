"""Block tags on the UR3 suction workcell (issue 12 item 5): its camera hangs 1.35 m up, so a small block's
4x4 ArUco tag spans ~2 px per bit and reads at some image scales only. Every tagged block of a simulated
frame (small ones across the far half of the board, large ones, a two-high pile) is detected with the id
the scene gave it (ground truth), none with another id; a small tag turned 45 deg near the base, which
reads at no scale, gets the destination of the one configured id of its colour (yellow: 100 -> place 1,
read from the workcell file). Real MuJoCo frame, real calibration from the tags."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import Scene, SceneObject, quat_from_yaw
from armlab.vision import calibrate_extrinsics, detect_blocks, load_perception_config
from armlab.workcell import load_workcell

WORKCELL = "ur3_suction"
EDGES_M = load_workcell(WORKCELL).blocks.edges_m
FILE = yaml.safe_load((Path(__file__).resolve().parents[2] / "config/workcells/ur3_suction.yaml").read_text())
YELLOW_PLACE = next(int(v["destination"]) for v in FILE["block_tags"]["ids"].values() if v["color"] == "yellow")
UNREADABLE = "u1"  # sort_by_tag L3 seed 18's block_2 on the UR3: read at no scale


def _block(oid, color, size, tag, x, y, yaw, z_base=0.0):
    return SceneObject(oid, "block", color, size, (x, y, z_base + EDGES_M[size] / 2), quat_from_yaw(yaw), tag, workcell=WORKCELL)


SCENE = Scene((
    _block("s1", "red", "small", 150, 0.121, 0.312, 0.35),  # read at 1x and 3x but not at 2x in the UR3 eval's seed 4
    _block("s2", "red", "small", 150, 0.162, 0.230, -0.6),
    _block("s3", "blue", "small", 200, -0.30, 0.36, 0.1),
    _block("s4", "yellow", "small", 100, 0.36, 0.30, 0.7),
    _block("s5", "blue", "small", 200, -0.05, 0.42, -0.3),
    _block("s6", "yellow", "small", 100, -0.42, 0.12, 0.5),
    _block("l1", "yellow", "large", 100, 0.02, 0.364, 0.2),
    _block("l2", "blue", "large", 200, 0.25, 0.10, -0.4),
    _block("p1", "red", "large", 150, -0.20, 0.22, 0.3),
    _block("p2", "blue", "small", 200, -0.20, 0.22, 0.3, z_base=EDGES_M["large"]),
    _block(UNREADABLE, "yellow", "small", 100, -0.1893, 0.0768, -0.7627),
), workcell=WORKCELL)


@pytest.fixture(scope="module")
def seen():
    look_pose_rad = np.asarray(load_workcell(WORKCELL).look_pose_rad, float)
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=18, workcell=WORKCELL), scene=SCENE) as cell:
        cell.apply_arm_reference(look_pose_rad, np.zeros(len(look_pose_rad)))
        cell.step(3.0)
        frame, truth = cell.render(), cell.truth()
    cfg = load_perception_config(workcell=WORKCELL)
    cal = calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    return detect_blocks(frame.color_bgr, frame.depth_mm, cal, cfg), truth


def test_every_tag_on_the_ur3_board_is_read_with_its_id(seen):
    blocks, truth = seen
    objects = {o["id"]: o for o in truth["objects"]}
    tops = [o for o in objects.values() if o["id"] not in ("p1", UNREADABLE)]  # p1 lies under p2
    for obj in tops:
        near = [b for b in blocks if math.dist(b.position_m[:2], obj["position_m"][:2]) < 0.015]
        assert near, f"{obj['id']} ({obj['color']} {obj['size']}) not detected"
        assert near[0].aruco_id == obj["aruco_id"], f"{obj['id']}: tag {obj['aruco_id']} read as {near[0].aruco_id}"
    assert sorted(b.aruco_id for b in blocks if b.aruco_id is not None) == sorted(o["aruco_id"] for o in tops)  # no extra ids


def test_an_unreadable_tag_goes_by_its_colour(seen):
    blocks, truth = seen
    obj = next(o for o in truth["objects"] if o["id"] == UNREADABLE)
    near = [b for b in blocks if math.dist(b.position_m[:2], obj["position_m"][:2]) < 0.015]
    assert near and near[0].color == "yellow" and near[0].aruco_id is None, near
    assert near[0].destination == YELLOW_PLACE
