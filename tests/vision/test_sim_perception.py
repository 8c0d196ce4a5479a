"""Perception on real simulated frames (MuJoCo) against the simulator's ground truth: tags,
calibration, pixel <-> world, blocks (stacks, distractors, tags, touching, occlusion), depth objects."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.scene import Scene, SceneObject, quat_from_yaw
from armlab.vision import (
    calibrate_extrinsics,
    detect_blocks,
    detect_objects_from_depth,
    detect_tags,
    pixel_to_world,
    project_grid,
    world_to_pixel,
)
from armlab.vision.evaluate import click_grid_errors, expected_tops, score_blocks
from armlab.vision.geometry import project_points
from armlab.workcell import load_workcell
from synth import render_sim


def _obj(oid, otype, color, size, x, y, yaw=0.0, z_base=0.0, aruco_id=None):
    height = {"large": 0.038, "small": 0.025}[size] if otype == "block" else 0.038
    return SceneObject(oid, otype, color, size, (x, y, z_base + height / 2), quat_from_yaw(yaw), aruco_id)


@pytest.fixture(scope="module")
def custom_frame():
    """Tagged tops (the sim draws DICT_4X4_250 tags), two touching blue cubes, a cylinder, and an orange
    cube under the arm."""
    scene = Scene(objects=(
        _obj("tagged", "block", "yellow", "large", 0.15, 0.26, yaw=0.3, aruco_id=100),
        _obj("twin_a", "block", "blue", "large", -0.22, 0.12),
        _obj("twin_b", "block", "blue", "large", -0.22 + 0.038, 0.12),
        _obj("red", "block", "red", "small", 0.27, 0.10, yaw=-0.5),
        _obj("cyl", "cylinder", "green", None, 0.02, 0.38),
        _obj("hidden", "block", "orange", "large", 0.0, 0.25),
        _obj("tagsmall", "block", "blue", "small", -0.10, 0.33, aruco_id=200),
    ))
    frame, truth = render_sim(scene, seed=7, arm_q=(0.0, 0.0, 0.0, 0.0, 0.0))
    return frame.color_bgr, frame, truth


@pytest.fixture(scope="module")
def event_cal(event_frame, cfg):
    frame, _ = event_frame
    return calibrate_extrinsics(frame.color_bgr, frame.intrinsics, cfg, depth_mm=frame.depth_mm)


def test_sim_tags_match_the_textures_corner_for_corner(event_frame, cfg):
    """The sim's tag textures and the config's corner layout agree (a rotated texture fails here)."""
    frame, truth = event_frame
    T = np.asarray(truth["camera"]["T_world_camera"])
    K = np.asarray(truth["camera"]["K"])
    found = detect_tags(frame.color_bgr, cfg)
    tags = [t for t in found if t.id in cfg.tags.board_tags]
    assert [t.id for t in tags] == [1, 2, 3, 4]
    assert {t.id for t in found} - {1, 2, 3, 4} <= {load_workcell().gripper.marker.id}  # and the gripper's tag, in view
    for tag in tags:
        expected = project_points(T, K, np.zeros(5), cfg.board_tag_corners_m(tag.id))
        assert np.max(np.linalg.norm(tag.corners_px - expected, axis=1)) < 1.0


def test_sim_calibration_finds_the_bumped_camera(event_frame, event_cal, cfg):
    frame, truth = event_frame
    T = np.asarray(truth["camera"]["T_world_camera"])
    K = np.asarray(truth["camera"]["K"])
    assert event_cal.reprojection_error_px < 0.5
    assert np.linalg.norm(event_cal.camera_position_m - T[:3, 3]) < 0.003
    assert event_cal.depth_check_error_m < 0.003
    assert np.linalg.norm(event_cal.T_world_camera_depth[:3, 3] - T[:3, 3]) < 0.02
    truth_grid = project_points(T, K, np.zeros(5), cfg.board.grid_points_m())
    assert np.max(np.linalg.norm(project_grid(event_cal, cfg) - truth_grid, axis=1)) < 1.0


def test_sim_click_to_world_on_the_board_and_on_a_block(event_frame, event_cal):
    frame, truth = event_frame
    errors = click_grid_errors(event_cal, truth, step_m=0.05)
    assert errors.size > 200 and errors.mean() < 0.001 and errors.max() < 0.003
    top = max(expected_tops(truth), key=lambda t: t.top_center_m[2])  # the tallest stack's top face
    u, v = world_to_pixel(event_cal, top.top_center_m)[0]
    with_depth = pixel_to_world(event_cal, u, v, depth_mm=frame.depth_mm)
    assert np.linalg.norm(with_depth - top.top_center_m) < 0.004
    at_height = pixel_to_world(event_cal, u, v, plane_z_m=float(top.top_center_m[2]))
    assert np.linalg.norm(at_height - top.top_center_m) < 0.002


def test_sim_blocks_on_an_event_scene(event_frame, event_cal, cfg):
    frame, truth = event_frame
    blocks = detect_blocks(frame.color_bgr, frame.depth_mm, event_cal, cfg)
    score = score_blocks(blocks, truth, frame.depth_mm)
    n_tops = sum(t.type == "block" for t in expected_tops(truth))
    assert score.failures == []
    assert score.true_positives == n_tops and n_tops >= 4
    assert score.level_correct == n_tops and max(b.stack_level for b in blocks if b.is_cube) >= 3
    assert score.distractors >= 2 and score.distractors_rejected == score.distractors
    assert max(score.position_errors_m) < 0.005 and np.mean(score.position_errors_m) < 0.002
    assert math.degrees(max(score.yaw_errors_rad)) < 4.0
    for block in blocks:
        assert -math.pi / 4 <= block.yaw_rad < math.pi / 4


def test_sim_tagged_touching_and_occluded_blocks(custom_frame, cfg):
    color, frame, truth = custom_frame
    cal = calibrate_extrinsics(color, frame.intrinsics, cfg, depth_mm=frame.depth_mm)
    blocks = detect_blocks(color, frame.depth_mm, cal, cfg)
    by_id = {o["id"]: np.asarray(o["position_m"]) for o in truth["objects"]}

    def near(obj_id, radius=0.012):
        return [b for b in blocks if np.linalg.norm(b.position_m[:2] - by_id[obj_id][:2]) < radius]

    tagged = near("tagged")
    assert len(tagged) == 1 and tagged[0].aruco_id == 100
    assert tagged[0].color == "yellow" and tagged[0].destination == 1 and tagged[0].is_cube
    small_tagged = near("tagsmall")  # a 15 mm tag on a 25 mm cube
    assert len(small_tagged) == 1 and small_tagged[0].aruco_id == 200 and small_tagged[0].destination == 3
    # Two touching blue cubes come out as two large blue cubes, each near its own centre.
    for twin in ("twin_a", "twin_b"):
        found = near(twin)
        assert len(found) == 1 and found[0].color == "blue" and found[0].size == "large" and found[0].is_cube
    assert [b.size for b in near("red")] == ["small"]
    assert all(not b.is_cube for b in near("cyl", 0.02)) and near("cyl", 0.02)
    hidden = [b for b in blocks if np.linalg.norm(b.position_m[:2] - by_id["hidden"][:2]) < 0.03]
    assert all(b.occluded for b in hidden)  # partly seen: flagged; fully hidden: not reported


def test_sim_objects_from_depth_any_colour(event_frame, event_cal, cfg):
    frame, truth = event_frame
    objects = detect_objects_from_depth(frame.depth_mm, event_cal, cfg)
    tops = expected_tops(truth)
    for top in tops:
        matches = [o for o in objects if np.linalg.norm(o.centroid_m[:2] - top.top_center_m[:2]) < 0.02]
        assert len(matches) == 1, f"{top.object_id}: {len(matches)} clusters"
        height = top.top_center_m[2] if top.type == "block" else None
        if height is not None:
            assert matches[0].height_m == pytest.approx(height, abs=0.004)
    # Besides the piles, only the arm (near the base) may form a cluster.
    extra = [o for o in objects if all(np.linalg.norm(o.centroid_m[:2] - t.top_center_m[:2]) >= 0.02 for t in tops)]
    assert all(np.linalg.norm(o.centroid_m[:2]) < 0.2 for o in extra)


@pytest.mark.parametrize(
    "gain_bgr", [(0.4, 0.4, 0.4), (1.4, 1.4, 1.4), (0.85, 1.0, 1.15), (1.15, 1.0, 0.85)], ids=["dim", "overexposed", "warm", "cool"]
)
def test_sim_block_colours_survive_lighting_changes(event_frame, event_cal, cfg, gain_bgr):
    frame, truth = event_frame
    relit = np.clip(frame.color_bgr * np.array(gain_bgr), 0, 255).astype(np.uint8)
    score = score_blocks(detect_blocks(relit, frame.depth_mm, event_cal, cfg), truth, frame.depth_mm)
    assert score.failures == [] and score.color_correct == score.true_positives >= 4
