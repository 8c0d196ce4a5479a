"""The workcell model: arm geometry against the kinematics FK, gripper span, tags and camera
(intrinsics, true pose, depth) against ground truth, and the camera noise model."""

import math

import cv2
import mujoco
import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.config import load_camera_config, nominal_T_world_camera
from armlab.kinematics import load_arm
from armlab.scene import Scene, SceneObject, quat_from_yaw
from armlab.workcell import load_workcell

TAG_CENTRES_M = load_workcell().board_tags.centres_m
TAG_SIZE_M = load_workcell().board_tags.size_m


@pytest.fixture(scope="module")
def cell():
    scene = Scene((
        SceneObject("big", "block", "red", "large", (0.12, 0.22, 0.019), quat_from_yaw(0.3)),
        SceneObject("small", "block", "blue", "small", (-0.15, 0.25, 0.0125), quat_from_yaw(-0.2)),
        SceneObject("top", "block", "green", "small", (0.20, 0.05, 0.038 + 0.0125), quat_from_yaw(0.1)),
        SceneObject("under", "block", "yellow", "large", (0.20, 0.05, 0.019), quat_from_yaw(0.1)),
    ))
    with SimWorkcell(SimWorkcellConfig(seed=4, color_noise=False, depth_noise=False), scene=scene) as sim:
        sim.step(0.2)
        yield sim


def test_model_gripper_point_matches_kinematics_fk_over_1000_random_joint_vectors(cell):
    arm = load_arm("rx200")
    rng = np.random.default_rng(0)
    q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(1000, 5))
    model = cell.model
    data = mujoco.MjData(model)
    site = model.site("gripper_point").id
    expected = arm.fk(q)[:, :3, 3]
    errors = []
    for qi, ei in zip(q, expected):
        data.qpos[cell._arm_qpos] = qi
        mujoco.mj_kinematics(model, data)
        errors.append(np.linalg.norm(data.site_xpos[site] - ei))
    assert max(errors) < 0.0005, f"largest model/FK gap {max(errors) * 1000:.3f} mm"


def test_servoed_arm_reaches_commanded_joints_and_fk_point(cell):
    from sim_helpers import move

    arm = load_arm("rx200")
    q = np.array([0.4, 0.2, 0.3, 0.9, -0.5])
    move(cell, q)
    cell.step(0.3)
    assert np.abs(cell.arm.read_joint_state().position_rad - q).max() < 0.003
    assert np.linalg.norm(cell.gripper_point_m() - arm.fk(q)[:3, 3]) < 0.0015


def test_finger_span_between_pads_is_18_to_62_mm(cell):
    model = cell.model
    data = mujoco.MjData(model)
    spans = []
    for offset in (0.015, 0.037):
        data.qpos[cell._finger_qpos] = offset
        mujoco.mj_kinematics(model, data)
        left, right = model.geom("left_pad").id, model.geom("right_pad").id
        half_thickness = model.geom_size[left][1]
        axis = data.geom_xmat[left].reshape(3, 3)[:, 1]  # pad thickness direction
        gap = abs(np.dot(data.geom_xpos[left] - data.geom_xpos[right], axis)) - 2 * half_thickness
        spans.append(gap)
    assert spans == pytest.approx([0.018, 0.062], abs=1e-6)


def project(T_world_camera, K, point_world):
    T_camera_world = np.linalg.inv(np.asarray(T_world_camera))
    p = T_camera_world[:3, :3] @ point_world + T_camera_world[:3, 3]
    return (np.asarray(K) @ p)[:2] / p[2], p[2]


def test_tags_are_detected_where_the_true_camera_projects_them(cell):
    frame = cell.render()
    truth = cell.truth()
    params = cv2.aruco.DetectorParameters()
    params.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_APRILTAG_36h11), params)
    corners, ids, _ = detector.detectMarkers(cv2.cvtColor(frame.color_bgr, cv2.COLOR_BGR2GRAY))
    assert ids is not None and sorted(ids.ravel().tolist()) == [1, 2, 3, 4]
    h = TAG_SIZE_M / 2
    errors = []
    for tag_corners, tag_id in zip(corners, ids.ravel()):
        x, y = TAG_CENTRES_M[int(tag_id)]
        # OpenCV corner order: the tag's top-left first, clockwise; the tag's top edge faces +y.
        world = [(x - h, y + h, 0), (x + h, y + h, 0), (x + h, y - h, 0), (x - h, y - h, 0)]
        for detected, corner in zip(tag_corners[0], world):
            expected, _ = project(truth["camera"]["T_world_camera"], truth["camera"]["K"], np.array(corner))
            errors.append(np.linalg.norm(detected - expected))
    assert np.mean(errors) < 0.5 and max(errors) < 1.2, errors


def test_depth_at_block_centres_equals_camera_to_top_face_distance(cell):
    frame = cell.render()
    truth = cell.truth()
    checked = 0
    for obj in truth["objects"]:
        if obj["id"] == "under":
            continue  # hidden under "top"
        edge = 0.038 if obj["size"] == "large" else 0.025
        top_centre = np.array(obj["position_m"]) + [0, 0, edge / 2]
        (u, v), z_camera = project(truth["camera"]["T_world_camera"], truth["camera"]["K"], top_centre)
        depth_mm = frame.depth_mm[int(round(v)), int(round(u))]
        assert abs(depth_mm - z_camera * 1000) <= 3.0, (obj["id"], depth_mm, z_camera * 1000)
        checked += 1
    assert checked == 3
    # The board plane: depth at a grid point matches too.
    (u, v), z_camera = project(truth["camera"]["T_world_camera"], truth["camera"]["K"], np.array([0.4, 0.4, 0.0]))
    assert abs(frame.depth_mm[int(round(v)), int(round(u))] - z_camera * 1000) <= 3.0


def test_true_camera_pose_is_bumped_within_limits_and_seeded():
    mount = load_camera_config().mount
    nominal = nominal_T_world_camera(mount)
    poses = []
    for seed in (1, 2):
        with SimWorkcell(SimWorkcellConfig(seed=seed)) as sim:
            poses.append(np.array(sim.truth()["camera"]["T_world_camera"]))
    with SimWorkcell(SimWorkcellConfig(seed=1, camera_pose_error=False)) as sim:
        assert np.allclose(sim.truth()["camera"]["T_world_camera"], nominal)
    with SimWorkcell(SimWorkcellConfig(seed=1)) as sim:
        assert np.allclose(sim.truth()["camera"]["T_world_camera"], poses[0])
    assert not np.allclose(poses[0], poses[1])
    for T in poses:
        assert np.all(np.abs(T[:3, 3] - nominal[:3, 3]) <= 0.02 * math.sqrt(3) + 1e-9)
        relative = nominal[:3, :3].T @ T[:3, :3]
        angle = math.degrees(math.acos(np.clip((np.trace(relative) - 1) / 2, -1, 1)))
        assert 0 < angle <= 3.0 + 1e-6
        assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-9)
    # Nominal mount per DESIGN §3: about 1 m up, looking down with 10-14 degrees of tilt.
    assert 0.9 < nominal[2, 3] < 1.1
    tilt = math.degrees(math.acos(-nominal[2, 2]))
    assert 10 <= tilt <= 14


def test_noise_is_on_by_default_and_l515_like():
    scene = Scene((SceneObject("b", "block", "red", "large", (0.0, 0.25, 0.019)),))
    with SimWorkcell(SimWorkcellConfig(seed=3), scene=scene) as sim:
        clean = sim.render_raw()
        noisy = sim.render()
        second = sim.render()
    config = load_camera_config()
    clean_bgr = cv2.cvtColor(clean.rgb, cv2.COLOR_RGB2BGR).astype(float)
    diff = noisy.color_bgr.astype(float) - clean_bgr
    assert abs(diff.std() - config.color.noise_std) < 0.5
    valid = noisy.depth_mm > 0
    depth_error = noisy.depth_mm[valid].astype(float) - clean.depth_m[valid] * 1000.0
    assert abs(depth_error.std() - math.hypot(config.depth.noise_std_mm, 0.29)) < 0.3
    assert 0.0005 < 1.0 - valid.mean() < 0.01
    assert not np.array_equal(noisy.color_bgr, second.color_bgr), "consecutive frames have fresh noise"
    assert noisy.color_bgr.shape == (720, 1280, 3) and noisy.depth_mm.dtype == np.uint16
    assert noisy.intrinsics.fx == pytest.approx(904.0)


def test_aruco_topped_blocks_show_their_tag_upright_on_the_top_face():
    scene = Scene((
        SceneObject("y", "block", "yellow", "large", (0.0, 0.25, 0.019), quat_from_yaw(0.0), aruco_id=100),
        SceneObject("r", "block", "red", "large", (0.15, 0.2, 0.019), quat_from_yaw(0.5), aruco_id=150),
        SceneObject("g", "block", "green", "large", (-0.15, 0.2, 0.019), quat_from_yaw(0.2)),
    ))
    with SimWorkcell(SimWorkcellConfig(seed=2, color_noise=False, depth_noise=False), scene=scene) as sim:
        sim.gripper.release()
        frame = sim.render()
        truth = sim.truth()
    detector = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_250))
    corners, ids, _ = detector.detectMarkers(frame.color_bgr)
    assert sorted(ids.ravel().tolist()) == [100, 150]
    by_id = {o.get("aruco_id"): o for o in truth["objects"]}
    for tag_corners, tag_id in zip(corners, ids.ravel()):
        obj = by_id[int(tag_id)]
        top = np.array(obj["position_m"]) + [0, 0, 0.019]
        (u, v), _ = project(truth["camera"]["T_world_camera"], truth["camera"]["K"], top)
        assert np.linalg.norm(tag_corners[0].mean(axis=0) - [u, v]) < 1.5
        # The tag's top edge (corner 0 -> 1) runs along the block's +x axis, seen from above.
        edge = tag_corners[0][1] - tag_corners[0][0]
        image_yaw = math.atan2(-edge[1], edge[0])  # image y points to world -y
        assert abs(math.remainder(image_yaw - obj["yaw_rad"], 2 * math.pi)) < math.radians(6)


def test_board_grid_lines_render_where_the_grid_is():
    with SimWorkcell(SimWorkcellConfig(seed=5, color_noise=False, depth_noise=False)) as sim:
        gray = cv2.cvtColor(sim.render().color_bgr, cv2.COLOR_BGR2GRAY).astype(int)
        truth = sim.truth()
    on_lines, off_lines = [], []
    for x in np.arange(-0.45, 0.451, 0.1):
        for y in np.arange(-0.125, 0.376, 0.1):  # grid lines at y = 25 mm + k * 50 mm (DESIGN §3)
            if math.hypot(x, y) < 0.2 or min(math.dist((x, y), c) for c in TAG_CENTRES_M.values()) < 0.04:
                continue  # the arm's base or a tag
            for dx, dy, bucket in ((0, 0, on_lines), (0.025, 0.025, off_lines)):
                (u, v), _ = project(truth["camera"]["T_world_camera"], truth["camera"]["K"], np.array([x + dx, y + dy, 0.0]))
                bucket.append(gray[int(round(v)), int(round(u))])
    assert len(on_lines) > 40
    assert max(on_lines) < min(off_lines) - 30, (max(on_lines), min(off_lines))
