"""The planning checks' clearance (armlab.motion.clearance) is the arm's body (armlab.devices.arm_body): the links'
capsules with the arm file's radii and the gripper's boxes, against obstacle boxes; its two overlap tests agree
with a brute-force measurement of the same shapes."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.kinematics import load_arm
from armlab.kinematics.arm_model import ArmModel
from armlab.kinematics.rotations import rotation_from_rotvec
from armlab.motion.clearance import (
    CLEARANCE_M,
    TOOL_CLEARANCE_M,
    _boxes_near_box,
    _segments_near_box,
    box_around,
    first_collision,
)

ARM = load_arm("rx200")


def sweep(q_from, q_to, samples: int = 60) -> JointTrajectory:
    t = np.linspace(0.0, 1.0, samples)
    return JointTrajectory(t * 2.0, np.asarray(q_from) + t[:, None] * (np.asarray(q_to) - np.asarray(q_from)))


def with_link_radii(radii) -> ArmModel:
    return ArmModel(ARM.config.model_copy(update={"link_radii_m": list(radii)}))


def test_the_links_are_as_thick_as_the_arm_file_says():
    """At home the RX200's forearm lies level over the board; a tower under it, its top a few millimetres below
    the forearm's underside less the margin, is cleared by the arm as its file describes it and hit by the same
    arm with 40 mm links (a check that ignored the file's radii answers both the same)."""
    home = np.zeros(ARM.dof)
    forearm = ARM.joint_frames(home)[2:4, :3, 3]  # elbow and wrist_angle origins
    assert abs(forearm[0, 2] - forearm[1, 2]) < 1e-9
    radius = ARM.config.link_radii_m[2]
    top = forearm[0, 2] - radius - CLEARANCE_M - 0.004
    mid = 0.5 * (forearm[0] + forearm[1])
    tower = box_around("the tower", mid[:2], 0.02, top)
    move = sweep([1.3, 0.0, 0.0, 0.0, 0.0], home)
    assert first_collision(ARM, move, [tower]) is None
    thick = with_link_radii([0.0, 0.04, 0.04, 0.04, 0.0])
    hit = first_collision(thick, move, [tower])
    assert hit is not None and "the tower" in hit and f"within {CLEARANCE_M * 1000:.0f} mm" in hit
    # The margin is the caller's: with none, the thin arm has 4 mm more room, still clear; with 10 mm more, it is not.
    assert first_collision(ARM, move, [tower], margin_m=CLEARANCE_M + 0.01) is not None


def test_the_open_palm_is_checked_unless_the_gripper_box_is():
    """A post 2 mm beside the gripper's open palm (57 mm from the gripper's axis: clear of the 30 mm around the
    gripper point the check had) is hit by the body's palm; clear_path's gripper_checked_m leaves the tool to fingers_hit."""
    home = np.zeros(ARM.dof)
    T = np.asarray(ARM.fk(home))
    palm_across = 0.049  # the palm reaches finger_offset_max_m + palm_side_margin_m across (config files)
    beside = T[:3, 3] - 0.08 * T[:3, 0] + (palm_across + 0.002 + 0.01) * T[:3, 1]  # its face 2 mm from the palm's side
    post = box_around("the post", beside[:2], 0.01, T[2, 3] + 0.05)
    move = sweep([0.0, -0.3, 0.0, 0.0, 0.0], home)  # the arm comes down in its own plane, the post beside it
    assert TOOL_CLEARANCE_M > 0.002
    assert first_collision(ARM, move, [post]) is not None
    assert first_collision(ARM, move, [post], margin_m=0.001) is None  # the tool keeps the smaller margin
    assert first_collision(ARM, move, [post], gripper_checked_m=0.07) is None


def _segment_box_distance(a, b, centre, half, samples: int = 2001) -> float:
    t = np.linspace(0.0, 1.0, samples)[:, None]
    points = a + t * (b - a)
    outside = np.maximum(np.abs(points - centre) - half, 0.0)
    return float(np.min(np.linalg.norm(outside, axis=1)))


def test_segments_near_a_box_against_brute_force():
    rng = np.random.default_rng(7)
    centre, half = np.array([0.1, 0.2, 0.05]), np.array([0.03, 0.02, 0.05])
    ends = rng.uniform(-0.1, 0.3, size=(400, 1, 2, 3)) + np.array([0.0, 0.1, -0.05])
    reach = np.array([0.02])
    near = _segments_near_box(ends.transpose(1, 0, 2, 3), reach, centre, half)[0]
    distance = np.array([_segment_box_distance(e[0, 0], e[0, 1], centre, half) for e in ends])
    assert near[distance < reach[0] - 1e-4].all()  # everything within reach is found
    assert (distance[near] < np.sqrt(3.0) * reach[0] + 1e-4).all()  # and nothing further than a grown corner
    assert near.sum() > 40 and (~near).sum() > 40


def test_oriented_boxes_against_an_axis_aligned_box_against_brute_force():
    rng = np.random.default_rng(8)
    centre, half = np.array([0.0, 0.0, 0.0]), np.array([0.03, 0.02, 0.04])
    count = 300
    poses = np.broadcast_to(np.eye(4), (count, 4, 4)).copy()
    poses[:, :3, :3] = rotation_from_rotvec(rng.normal(size=(count, 3)))
    poses[:, :3, 3] = rng.uniform(-0.08, 0.08, size=(count, 3))
    halves = np.array([[0.02, 0.01, 0.03]])
    overlap = _boxes_near_box(poses[:, None], halves, centre, half)[:, 0]
    grid = np.stack(np.meshgrid(*[np.linspace(-1.0, 1.0, 15)] * 3), axis=-1).reshape(-1, 3) * halves[0]
    inside = np.array([np.any(np.all(np.abs(grid @ T[:3, :3].T + T[:3, 3] - centre) <= half, axis=1)) for T in poses])
    assert overlap[inside].all()  # a sampled point of the part inside the box: the test sees the overlap
    assert (overlap & ~inside).sum() <= 0.05 * count  # and the rest are overlaps between grid points
    assert inside.sum() > 30 and (~overlap).sum() > 30


@pytest.mark.parametrize("edge_m", [0.025, 0.04])
def test_a_held_block_hangs_below_the_gripper(edge_m):
    """Top-down over a low block, the held block (a full edge beyond the gripper point) hits it where the empty
    gripper (its fingers' tips a few millimetres beyond) does not."""
    q = np.asarray(ARM.ik((0.0, 0.25, 0.09), pitch=np.pi / 2))
    T = np.asarray(ARM.fk(q))
    low = box_around("the low block", T[:2, 3], 0.02, T[2, 3] - 0.02)
    above = q.copy()
    above[0] += 0.6
    move = sweep(above, q)
    assert first_collision(ARM, move, [low], margin_m=0.005) is None
    assert first_collision(ARM, move, [low], margin_m=0.005, held_edge_m=edge_m) is not None
