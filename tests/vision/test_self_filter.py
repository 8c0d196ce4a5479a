"""The robot self-filter on the real simulation: a block held in the gripper and the arm's links never
become detections, across arm poses (over blocks, low near the board, high), while the board's blocks
under and near the arm are still detected when visible. Checked against the simulator's ground truth;
the same frames without the filter do report the held block or the arm (so these tests can fail)."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from armlab.devices.arm_body import load_arm_body
from armlab.devices.camera import Frame
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.errors import ConfigError
from armlab.kinematics.arm_model import ArmModel, load_arm
from armlab.motion import plan_joint_move
from armlab.scene import Scene, SceneObject, quat_from_yaw
from armlab.station.perception import analyse_frame, with_robot_state
from armlab.station.telemetry import block_to_dict
from armlab.vision import PerceptionPipeline, calibrate_extrinsics, load_perception_config
from armlab.vision.config import SelfFilterConfig
from armlab.vision.self_filter import RobotSelfFilter, robot_volume

EDGE_M = {"large": 0.038, "small": 0.025}
HELD_XY, HELD_YAW = (0.10, 0.22), 0.2


def _block(oid, color, size, x, y, yaw=0.0, z_base=0.0):
    return SceneObject(oid, "block", color, size, (x, y, z_base + EDGE_M[size] / 2), quat_from_yaw(yaw))


SCENE = Scene(objects=(
    _block("held", "red", "large", *HELD_XY, yaw=HELD_YAW),
    _block("blue", "blue", "large", -0.15, 0.25),
    _block("green", "green", "small", 0.0, 0.33),
    _block("yellow", "yellow", "large", 0.21, 0.06, yaw=-0.3),
    _block("orange", "orange", "large", -0.22, 0.08),
    _block("violet", "violet", "small", -0.22, 0.08, z_base=0.038),
))


def _quat_matrix(q):
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def _corners(obj: dict, scale: float = 1.0) -> np.ndarray:
    """(8, 3) world corners of a true block (scaled about its centre)."""
    half = 0.5 * EDGE_M[obj["size"]] * scale
    local = np.array([[x, y, z] for x in (-half, half) for y in (-half, half) for z in (-half, half)])
    return local @ _quat_matrix(obj["quat_wxyz"]).T + np.asarray(obj["position_m"])


def _top_centre(obj: dict) -> np.ndarray:
    return np.asarray(obj["position_m"]) + _quat_matrix(obj["quat_wxyz"])[:, 2] * 0.5 * EDGE_M[obj["size"]]


def _project(truth: dict, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(pixels (N, 2), camera depth m (N,)) of world points through the TRUE camera."""
    T_camera_world = np.linalg.inv(np.asarray(truth["camera"]["T_world_camera"]))
    cam = points_m @ T_camera_world[:3, :3].T + T_camera_world[:3, 3]
    uv = cam @ np.asarray(truth["camera"]["K"]).T
    return uv[:, :2] / uv[:, 2:3], cam[:, 2]


def _top_visible(truth: dict, obj: dict, depth_mm: np.ndarray) -> bool:
    """True if >= 90 % of a 5x5 grid on the block's top face shows that face in the depth image."""
    half = 0.4 * EDGE_M[obj["size"]]
    R, top = _quat_matrix(obj["quat_wxyz"]), _top_centre(obj)
    grid = [top + a * R[:, 0] + b * R[:, 1] for a in np.linspace(-half, half, 5) for b in np.linspace(-half, half, 5)]
    px, z_m = _project(truth, np.array(grid))
    u, v = np.round(px).astype(int).T
    measured = depth_mm[v, u].astype(float)
    valid = measured > 0
    return np.count_nonzero(np.abs(measured[valid] - 1000 * z_m[valid]) < 5.0) >= 0.9 * np.count_nonzero(valid)


def _hull_pixels(truth: dict, points_m: np.ndarray, shape) -> np.ndarray:
    """(H, W) bool: the convex hull of the points' true projections."""
    px, _ = _project(truth, points_m)
    out = np.zeros(shape, np.uint8)
    cv2.fillConvexPoly(out, cv2.convexHull(np.round(px).astype(np.int32)), 1)
    return out.view(bool)


@pytest.fixture(scope="module")
def arm():
    return load_arm("rx200")


@pytest.fixture(scope="module")
def run(arm, cfg):
    """Pick the red block and carry it through seven poses; per pose the frame, truth and the
    perception with and without the self-filter."""
    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=5, camera_pose_error=True))
    cell.start()
    try:
        cell.set_scene(SCENE)
        cell.step(0.5)
        parked = cell.render()
        cal = calibrate_extrinsics(parked.color_bgr, parked.intrinsics, cfg, depth_mm=parked.depth_mm)
        pipeline = PerceptionPipeline(cfg, arm)
        held_top = np.array([*HELD_XY, EDGE_M["large"]])

        def go(q_goal):
            q_now = cell.arm.read_joint_state().position_rad
            cell.arm.command_trajectory(plan_joint_move(q_now, q_goal, arm), wait=True)
            cell.step(0.3)

        def to(position_m, yaw=HELD_YAW, pitch=None):
            go(arm.ik(position_m, pitch=pitch, yaw=yaw, q_seed=cell.arm.read_joint_state().position_rad))

        def travel(position_m, pitch=None):
            """Up to 150 mm, across, then down: the held block sweeps over the others, not through them."""
            to([*cell.gripper_point_m()[:2], 0.15])
            to([*position_m[:2], 0.15])
            to(position_m, pitch=pitch)

        poses = {}

        def look(name):
            frame, truth = cell.render(), cell.truth()
            filtered = pipeline.process(frame.color_bgr, frame.depth_mm, cal, layers=None,
                                        arm_joints_rad=frame.arm_joints_rad, frame_time_s=frame.timestamp_s)
            unfiltered = pipeline.process(frame.color_bgr, frame.depth_mm, cal, layers=None)
            poses[name] = {"frame": frame, "truth": truth, "filtered": filtered, "unfiltered": unfiltered}

        cell.gripper.release()
        to(held_top + [0, 0, 0.08])
        look("hover over the block")
        to(held_top - [0, 0, 0.015])
        cell.gripper.grasp()
        look("grasped, low at the board")
        to(held_top + [0, 0, 0.08])
        look("lifted")
        travel([-0.15, 0.25, 0.038 + 0.09])
        look("reaching over the blue block")
        travel([0.09, 0.10, 0.045])
        look("low near the yellow block")
        travel([-0.30, 0.16, 0.07], pitch=math.radians(45))
        look("far left, pitched")
        go(np.zeros(5))
        look("high: home pose over the green block")
        yield {"poses": poses, "cal": cal, "cell": cell}
    finally:
        cell.close()


def _holding(pose) -> str | None:
    return pose["truth"]["gripper"]["holding_id"]


def _foreign(blocks, truth) -> list[str]:
    """Detections that are not a board block: farther than 10 mm (3-D) from every true top centre of
    a block other than the held one (a partly hidden block flagged occluded: 20 mm)."""
    held = truth["gripper"]["holding_id"]
    tops = [_top_centre(o) for o in truth["objects"] if o["id"] != held]
    out = []
    for b in blocks:
        nearest = min(np.linalg.norm(b.position_m - t) for t in tops)
        if nearest > (0.020 if b.occluded else 0.010):
            out.append(f"{b.color} {b.size} cube={b.is_cube} at {np.round(b.position_m * 1000).tolist()} mm ({nearest * 1000:.0f} mm off)")
    return out


def test_the_arm_held_the_block_through_the_poses(run):
    """The scenario is what it claims: six or more poses, the red block in the gripper in all but the first."""
    poses = run["poses"]
    assert len(poses) >= 6
    holding = [_holding(p) for p in poses.values()]
    assert holding[0] is None and all(h == "held" for h in holding[1:]), holding


def test_neither_the_held_block_nor_the_arm_is_ever_a_detection(run):
    failures = {name: _foreign(p["filtered"].blocks, p["truth"]) for name, p in run["poses"].items()}
    assert all(not f for f in failures.values()), failures


def test_without_the_filter_the_held_block_and_the_arm_are_reported(run):
    """The same frames unfiltered: the held block or the arm is reported (what the filter removes)."""
    failures = {name: _foreign(p["unfiltered"].blocks, p["truth"]) for name, p in run["poses"].items()}
    assert sum(bool(f) for f in failures.values()) >= 3, failures


def test_visible_board_blocks_under_and_near_the_arm_are_still_detected(run):
    checked = 0
    for name, pose in run["poses"].items():
        truth, depth = pose["truth"], pose["frame"].depth_mm
        for obj in truth["objects"]:
            if obj["id"] == _holding(pose) or not _top_visible(truth, obj, depth):
                continue
            checked += 1
            errors = [np.linalg.norm(b.position_m - _top_centre(obj)) for b in pose["filtered"].blocks]
            assert errors and min(errors) < 0.010, f"{name}: {obj['id']} visible but not detected"
            match = pose["filtered"].blocks[int(np.argmin(errors))]
            assert match.color == obj["color"] and match.size == obj["size"], f"{name}: {obj['id']} as {match}"
    assert checked >= 6 * 4  # most of the five board piles' tops are visible in every pose


def test_detections_carry_the_frame_time_and_the_arm_pose(run):
    for pose in run["poses"].values():
        frame = pose["frame"]
        assert pose["filtered"].blocks
        for block in pose["filtered"].blocks:
            assert block.seen_time_s == frame.timestamp_s
            np.testing.assert_allclose(block.seen_arm_joints_rad, frame.arm_joints_rad)
            assert block_to_dict(0, block)["seen_time_s"] == frame.timestamp_s


def test_sim_frames_carry_the_joints_and_gripper_they_were_rendered_with(run):
    for pose in run["poses"].values():
        np.testing.assert_array_equal(pose["frame"].arm_joints_rad, pose["truth"]["arm"]["position_rad"])
        assert pose["frame"].gripper_closed == (_holding(pose) is not None)


def test_the_held_block_is_masked_and_a_block_under_the_hovering_gripper_is_not(run):
    lifted = run["poses"]["lifted"]
    truth, mask = lifted["truth"], lifted["filtered"].robot_mask
    held = next(o for o in truth["objects"] if o["id"] == "held")
    held_px = _hull_pixels(truth, _corners(held), mask.shape)
    assert np.count_nonzero(held_px) > 1500
    assert np.count_nonzero(mask & held_px) / np.count_nonzero(held_px) > 0.99

    hover = run["poses"]["hover over the block"]
    truth, mask, depth = hover["truth"], hover["filtered"].robot_mask, hover["frame"].depth_mm
    below = next(o for o in truth["objects"] if o["id"] == "held")  # still on the board, 80 mm under the gripper
    block_px = _hull_pixels(truth, _corners(below), mask.shape)
    # Its pixels that see the block, not the gripper above it, and are more than 3 px from the
    # gripper's outline (the mask may cover the robot's edge by up to pixel_step pixels).
    gripper_z_m = _project(truth, np.asarray(truth["gripper"]["position_m"])[None])[1][0]
    sees_robot = ((depth > 0) & (depth < 1000 * (gripper_z_m + 0.05))).astype(np.uint8)
    near_robot = cv2.dilate(sees_robot, np.ones((7, 7), np.uint8)).view(bool)
    sees_block = block_px & (depth > 1000 * (gripper_z_m + 0.05)) & ~near_robot
    assert np.count_nonzero(sees_block) > 1000
    assert np.count_nonzero(mask & sees_block) / np.count_nonzero(sees_block) < 0.01
    assert np.count_nonzero(mask) > 5000  # the arm itself is masked


def test_a_real_camera_frame_gets_the_joints_from_the_arm(run, arm, cfg):
    """A frame without joints (as a real camera gives) is completed from the arm and gripper;
    analyse_frame puts the joints and the robot mask in the Perception snapshot and stamps the blocks."""
    cell = run["cell"]
    sim_frame = cell.render()
    bare = Frame(sim_frame.color_bgr, sim_frame.depth_mm, sim_frame.timestamp_s, sim_frame.sequence, sim_frame.intrinsics)
    assert bare.arm_joints_rad is None and bare.gripper_closed is None and with_robot_state(bare, None) is bare
    completed = with_robot_state(bare, cell.arm, cell.gripper)
    np.testing.assert_array_equal(completed.arm_joints_rad, cell.arm.read_joint_state().position_rad)
    assert completed.gripper_closed is True  # it holds the red block
    perception = analyse_frame(PerceptionPipeline(cfg, arm), completed, run["cal"])
    assert perception.arm_joints_rad == tuple(completed.arm_joints_rad.tolist())
    assert perception.robot_mask is not None and perception.robot_mask.shape == bare.depth_mm.shape
    assert perception.blocks and all(b.seen_time_s == bare.timestamp_s for b in perception.blocks)
    assert analyse_frame(PerceptionPipeline(cfg, arm), bare, run["cal"]).robot_mask is None  # no joints: no filter


def test_volume_contains_the_links_and_what_is_between_the_fingers_only(arm):
    cfg = SelfFilterConfig()
    q = arm.ik([0.0, 0.25, 0.10])  # straight down, gripper point 100 mm above the board
    volume = robot_volume(arm, q, cfg)
    frames = arm.joint_frames(q)
    assert volume.contains(frames[:, :3, 3]).all()
    gripper = frames[-1, :3, 3]
    inside = [gripper + [0, 0, -0.03], gripper + [0, 0, 0.05]]  # a held block's bottom, the wrist
    outside = [gripper + [0, 0, -0.07], [0.0, 0.25, 0.038], gripper + [0.1, 0, 0], [0.3, 0.3, 0.02]]
    assert volume.contains(np.array(inside)).all()
    assert not volume.contains(np.array(outside)).any()
    empty_hand = robot_volume(arm, q, cfg, held_block_edge_m=0.0)
    assert not empty_hand.contains(np.array([gripper + [0, 0, -0.035]])).any()


def test_the_volume_is_the_arm_body_grown_by_the_margin(arm):
    """The self-filter's volume is the arm's body (armlab.devices.arm_body): at random joints every point on the
    surface of the body's links, housings and gripper parts is inside it; a point a few millimetres beyond the
    forearm's grown surface is outside, and inside for the same arm with thicker links in its file (a filter with
    radii of its own answers both the same)."""
    cfg = SelfFilterConfig()
    body = load_arm_body("rx200")
    rng = np.random.default_rng(11)
    unit = np.array(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1])).reshape(3, -1).T
    thick = ArmModel(arm.config.model_copy(update={"link_radii_m": [0.0, 0.03, 0.03, 0.03, 0.0]}))
    compared = 0
    for _ in range(10):
        q = rng.uniform(arm.lower_rad, arm.upper_rad)
        volume = robot_volume(arm, q, cfg, held_block_edge_m=0.0)
        placed = body.place(arm, q)
        for k, part in enumerate(placed.parts):
            T = placed.poses[0, k]
            if part.shape == "box":
                local = unit * np.asarray(part.size_m)
            else:  # the rim of each end and the middle of a capsule or cylinder
                radius, half = part.size_m[:2]
                ring = np.array([[radius * np.cos(a), radius * np.sin(a)] for a in np.linspace(0, 2 * np.pi, 8)])
                local = np.array([[x, y, z] for x, y in ring for z in (-half, 0.0, half)])
            assert volume.contains(local @ T[:3, :3].T + T[:3, 3]).all(), part.name
        (k,) = [k for k, part in enumerate(placed.parts) if part.name == "elbow_capsule"]
        T, radius = placed.poses[0, k], placed.parts[k].size_m[0]
        beyond = T[:3, 3] + (radius + cfg.margin_m + 0.004) * T[:3, 0]  # off the forearm's middle, square to it
        if robot_volume(arm, q, cfg, held_block_edge_m=0.0).contains(beyond[None]).any():
            continue  # another part (the upper arm folded against it) is there
        assert robot_volume(thick, q, cfg, held_block_edge_m=0.0).contains(beyond[None]).all()
        compared += 1
    assert compared >= 5


def test_bad_input_is_refused(run, arm, cfg):
    pose = run["poses"]["lifted"]
    frame, cal = pose["frame"], run["cal"]
    with pytest.raises(ValueError, match="arm_model"):
        PerceptionPipeline(cfg).process(frame.color_bgr, frame.depth_mm, cal, arm_joints_rad=np.zeros(5))
    pipeline = PerceptionPipeline(cfg, arm)
    with pytest.raises(ValueError, match="shape"):
        pipeline.process(frame.color_bgr, frame.depth_mm, cal, arm_joints_rad=np.zeros(4))
    with pytest.raises(ValueError, match="finite"):
        pipeline.process(frame.color_bgr, frame.depth_mm, cal, arm_joints_rad=[0.0, float("nan"), 0, 0, 0])
    with pytest.raises(ValueError, match="held_block_edge_m"):
        pipeline.process(frame.color_bgr, frame.depth_mm, cal, arm_joints_rad=np.zeros(5), held_block_edge_m=-0.01)
    with pytest.raises(ValueError, match="uint16"):
        RobotSelfFilter(arm, cfg.self_filter).mask(frame.depth_mm[:100], cal, np.zeros(5))


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"margin_m": -0.01}, "margin_m"),
        ({"margin_m": float("nan")}, "margin_m"),
        ({"pixel_step": 0}, "pixel_step"),
        ({"inflate": 1.0}, "inflate"),
    ],
)
def test_bad_self_filter_config_is_a_clear_error(tmp_path, change, field):
    import yaml

    from armlab.config import config_dir

    data = yaml.safe_load((config_dir() / "vision.yaml").read_text())
    data["self_filter"].update(change)
    path = tmp_path / "vision.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match=f"self_filter.*{field}"):
        load_perception_config(path)


def test_a_block_under_the_parked_empty_gripper_is_seen_and_masked_only_when_it_could_be_held(arm, cfg):
    """The sleep pose parks the open gripper 74 mm above the board at y = 123 mm: a block under it is
    the scene, not a held block, unless the gripper is closed (then the filter must assume it holds one)."""
    blue = _block("blue", "blue", "large", 0.011, 0.133)
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=21, camera_pose_error=True)) as cell:
        cell.set_scene(Scene(objects=(blue,)))
        cell.step(0.5)
        open_frame = cell.render()
        cal = calibrate_extrinsics(open_frame.color_bgr, open_frame.intrinsics, cfg)
        pipeline = PerceptionPipeline(cfg, arm)
        cell.gripper.grasp()  # closes on nothing
        closed_frame = cell.render()
        top = _top_centre(cell.truth()["objects"][0])
    assert open_frame.gripper_closed is False and closed_frame.gripper_closed is True
    seen = analyse_frame(pipeline, open_frame, cal).blocks
    assert len(seen) == 1 and np.linalg.norm(seen[0].position_m - top) < 0.010
    assert analyse_frame(pipeline, closed_frame, cal).blocks == ()
