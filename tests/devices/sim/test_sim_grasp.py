"""Physical grasping and stacking: grasps hold by pad friction only when both pads press on opposite
faces, slip stays under 1 mm for grasps within +-8 mm and +-15 deg, a grasp beside the block lifts
nothing, stacks of six stand and a block released half off a stack falls."""

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.scene import Scene, SceneObject, quat_from_yaw
from sim_helpers import move_to, topdown_ik

BLOCK_XY = np.array([0.05, 0.25])
BLOCK_YAW = 0.2


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(seed=0, color_noise=False, depth_noise=False)) as sim:
        yield sim


def quat_to_matrix(quat_wxyz):
    w, x, y, z = quat_wxyz
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def block_in_gripper_frame(truth):
    """The block's position relative to the gripper point, in the gripper frame (slip measure)."""
    R = quat_to_matrix(truth["gripper"]["quat_wxyz"])
    offset = np.array(truth["objects"][0]["position_m"]) - np.array(truth["gripper"]["position_m"])
    return R.T @ offset


def pick_and_carry(cell, size, along_m=0.0, across_m=0.0, yaw_error_rad=0.0):
    """Grasp a block with the given error, lift 120 mm, carry it 130 mm sideways; returns results."""
    edge = 0.038 if size == "large" else 0.025
    centre = np.array([*BLOCK_XY, edge / 2])
    cell.set_scene(Scene((SceneObject("b", "block", "orange", size, tuple(centre), quat_from_yaw(BLOCK_YAW)),)))
    cell.gripper.release()
    grasp_yaw = BLOCK_YAW + yaw_error_rad
    move_to(cell, centre + [0, 0, 0.08], grasp_yaw)
    finger_axis = quat_to_matrix(cell.truth()["gripper"]["quat_wxyz"])[:, 1]
    along_axis = np.cross([0.0, 0.0, 1.0], finger_axis)
    target = centre + along_m * along_axis + across_m * finger_axis
    move_to(cell, target + [0, 0, 0.08], grasp_yaw)
    move_to(cell, target, grasp_yaw)
    cell.gripper.grasp()
    grasped = cell.truth()
    state = cell.gripper.read_state()
    move_to(cell, target + [0, 0, 0.12], grasp_yaw)
    move_to(cell, target + [0.12, -0.05, 0.12], grasp_yaw, speed_rad_s=2.0)
    cell.step(0.5)
    carried = cell.truth()
    slip_m = np.linalg.norm(block_in_gripper_frame(carried) - block_in_gripper_frame(grasped))
    return {"state": state, "grasped": grasped, "carried": carried, "slip_m": slip_m,
            "lift_m": carried["objects"][0]["position_m"][2] - edge / 2}


@pytest.mark.parametrize(
    "size,along_m,across_m,yaw_error_deg",
    [
        ("large", 0.0, 0.0, 0.0),
        ("small", 0.0, 0.0, 0.0),
        ("large", 0.008, 0.0, 0.0),
        ("large", -0.008, 0.006, 0.0),
        ("large", 0.0, 0.0, 15.0),
        ("small", 0.006, -0.004, -15.0),
    ],
)
def test_grasp_within_tolerance_lifts_and_carries_without_slipping(cell, size, along_m, across_m, yaw_error_deg):
    result = pick_and_carry(cell, size, along_m, across_m, np.radians(yaw_error_deg))
    assert result["state"].holding
    assert result["grasped"]["gripper"]["holding_id"] == "b"
    assert result["grasped"]["gripper"]["left_contacts"] == ["b"] == result["grasped"]["gripper"]["right_contacts"]
    assert result["lift_m"] > 0.11
    assert result["slip_m"] < 0.001, f"slipped {result['slip_m'] * 1000:.2f} mm"


def test_grasp_whose_pads_miss_the_block_lifts_nothing(cell):
    result = pick_and_carry(cell, "large", along_m=0.03)
    assert not result["state"].holding
    assert result["state"].width_m == pytest.approx(0.018, abs=0.001)
    assert result["grasped"]["gripper"]["holding_id"] is None
    assert abs(result["lift_m"]) < 0.003


def test_closing_on_nothing_is_not_holding(cell):
    cell.set_scene(Scene())
    cell.gripper.grasp()
    state = cell.gripper.read_state()
    assert not state.holding and state.command == "grasp"
    cell.gripper.release()
    assert cell.gripper.read_state().width_m == pytest.approx(0.062, abs=0.001)


def test_fingers_halted_mid_stroke_hold_nothing(cell):
    """Issue 21: stop() while closing on nothing halts the fingers half way; they are driven closed, stopped
    and far from fully closed, yet nothing resists them: not holding (was True: read from the finger width)."""
    cell.set_scene(Scene())
    cell.gripper.release()
    cell.gripper.grasp(wait=False)
    cell.step(0.05)
    cell.gripper.stop()
    cell.step(1.0)
    state = cell.gripper.read_state()
    assert state.command == "grasp" and state.width_m > cell.gripper.min_width_m + 0.01  # really halted mid-stroke
    assert not state.holding and cell.truth()["gripper"]["holding_id"] is None
    cell.gripper.release()


def stack(n, x=0.0, y=0.25, offset_top_m=0.0):
    objects = []
    for i in range(n):
        dx = offset_top_m if i == n - 1 else 0.0
        objects.append(SceneObject(f"s{i}", "block", "red", "large", (x + dx, y, 0.019 + 0.038 * i), quat_from_yaw(0.0)))
    return Scene(tuple(objects))


def test_stack_of_six_large_blocks_stands(cell):
    scene = stack(6, x=-0.2, y=0.2)
    cell.set_scene(scene)
    cell.step(3.0)
    for obj, start in zip(cell.truth()["objects"], scene.objects):
        assert np.linalg.norm(np.array(obj["position_m"]) - start.position_m) < 0.001, obj["id"]


def test_block_released_half_off_a_stack_falls(cell):
    cell.set_scene(stack(3, x=-0.2, y=0.2, offset_top_m=0.024))  # centre of mass beyond the edge
    cell.step(1.5)
    top = cell.truth()["objects"][-1]
    assert top["position_m"][2] < 0.038 * 2 + 0.019 - 0.01
    cell.set_scene(stack(3, x=-0.2, y=0.2, offset_top_m=0.012))  # centre of mass still supported
    cell.step(1.5)
    assert cell.truth()["objects"][-1]["position_m"][2] == pytest.approx(0.038 * 2 + 0.019, abs=0.001)


def test_a_45_degree_grasp_is_decided_by_the_contacts(cell):
    """Pads closing on the cube's vertical edges: no rule aligns or welds it; the pads stop on the edges
    (span near the 53.7 mm diagonal) and whatever holds it is the two pads' contacts."""
    result = pick_and_carry(cell, "large", yaw_error_rad=np.radians(45))
    width = result["state"].width_m
    assert 0.050 < width < 0.0538
    gripper = result["grasped"]["gripper"]
    assert (gripper["holding_id"] == "b") == (gripper["left_contacts"] == ["b"] == gripper["right_contacts"])


def test_grip_comes_from_pad_friction_not_from_proximity(tmp_path):
    """The same centred grasp with nearly frictionless pads lifts nothing."""
    import yaml

    from armlab.config import config_dir

    data = yaml.safe_load((config_dir() / "sim.yaml").read_text())
    data["gripper"]["pad_friction"] = [0.005, 0.0001, 0.0001]  # 2 pads x 10 N x 0.005 < the 0.37 N weight
    data["objects"]["friction"] = [0.005, 0.0001, 0.0001]
    slippery = tmp_path / "slippery.yaml"
    slippery.write_text(yaml.safe_dump(data))
    with SimWorkcell(SimWorkcellConfig(seed=0, sim=str(slippery), color_noise=False, depth_noise=False)) as sim:
        result = pick_and_carry(sim, "large")
    assert result["grasped"]["gripper"]["left_contacts"] == ["b"]  # the pads did close on it
    assert result["lift_m"] < 0.02


def test_distractors_rest_stably_where_they_were_placed(cell):
    from armlab.scene.model import DISTRACTOR_TYPES, object_dimensions_m

    objects = []
    for i, kind in enumerate(DISTRACTOR_TYPES):
        for j, size in enumerate((None, "small")):
            height = object_dimensions_m(kind, size)[2]
            position = (-0.3 + 0.2 * i, 0.3 - 0.12 * j, height / 2)
            objects.append(SceneObject(f"{kind}_{j}", kind, "green", size, position, quat_from_yaw(0.3 * i)))
    scene = Scene(tuple(objects))
    cell.set_scene(scene)
    cell.step(1.5)
    for obj, start in zip(cell.truth()["objects"], scene.objects):
        assert np.linalg.norm(np.array(obj["position_m"]) - start.position_m) < 0.002, obj["id"]
        assert abs(obj["yaw_rad"] - start.yaw_rad) < 0.02, obj["id"]


@pytest.mark.parametrize("offset_m,falls", [(0.0, False), (0.024, True)])
def test_block_released_by_the_gripper_on_a_stack_stays_or_falls(cell, offset_m, falls):
    """Carry a block onto a two-block stack and open the fingers: centred it stays, half off it falls."""
    stack_xy = np.array([-0.15, 0.22])
    loose = np.array([0.1, 0.22, 0.019])
    cell.set_scene(Scene((
        SceneObject("s0", "block", "red", "large", (*stack_xy, 0.019)),
        SceneObject("s1", "block", "orange", "large", (*stack_xy, 0.057)),
        SceneObject("b", "block", "yellow", "large", tuple(loose)),
    )))
    cell.gripper.release()
    move_to(cell, loose + [0, 0, 0.06])
    move_to(cell, loose)
    cell.gripper.grasp()
    assert cell.gripper.read_state().holding
    drop = np.array([stack_xy[0] + offset_m, stack_xy[1], 0.076 + 0.019 + 0.002])
    move_to(cell, drop + [0, 0, 0.06])
    move_to(cell, drop)
    cell.gripper.release()
    move_to(cell, drop + [0, 0, 0.06])
    cell.step(1.5)
    placed = {o["id"]: o for o in cell.truth()["objects"]}["b"]
    if falls:
        assert placed["position_m"][2] < 0.076
    else:
        assert placed["position_m"][2] == pytest.approx(0.095, abs=0.002)
        assert np.linalg.norm(np.array(placed["position_m"][:2]) - drop[:2]) < 0.003


def test_a_stop_in_the_jolt_of_an_arm_halt_keeps_squeezing_the_block(cell):
    """Issue 18/21: an e-stop halts the arm and then the fingers. Just after the arm's halt the fingers jiggle, so for
    ~90 ms the gripper does not read as holding (its stillness test); a finger stop that landed then (under load, at
    the next tick) set the fingers' reference where they stood, the squeeze went and the carried block fell (a
    fresh-clone run, 3 workers). Once it has held since its grasp, a stop keeps squeezing whatever it reads."""
    centre = np.array([0.0, 0.25, 0.019])
    cell.set_scene(Scene((SceneObject("b", "block", "red", "large", tuple(centre), quat_from_yaw(0.0)),)))
    cell.gripper.release()
    move_to(cell, centre + [0, 0, 0.08])
    move_to(cell, centre)
    cell.gripper.grasp()
    assert cell.gripper.read_state().holding
    q0 = cell.arm.read_joint_state().position_rad
    q1 = topdown_ik(centre + [0.1, -0.05, 0.12], 0.0, 0.0)
    times = np.linspace(0.0, 0.8, 81)
    s = times / 0.8
    cell.arm.command_trajectory(JointTrajectory(times, q0 + np.outer(10 * s**3 - 15 * s**4 + 6 * s**5, q1 - q0)), wait=False)
    cell.step(0.3)
    cell.arm.stop()  # the e-stop's arm halt: the fingers jiggle with the jolt
    for _ in range(50):
        cell.step(0.002)
        if not cell.gripper.read_state().holding:
            break
    assert not cell.gripper.read_state().holding, "the jolt did not unsettle the grip reading: nothing tested"
    cell.gripper.stop()  # the e-stop's finger halt, landing in the jolt
    carried_z = cell.truth()["objects"][0]["position_m"][2]
    assert carried_z > 0.04  # lifted off the board
    cell.step(1.5)
    truth = cell.truth()
    assert truth["gripper"]["holding_id"] == "b", truth["gripper"]
    assert abs(truth["objects"][0]["position_m"][2] - carried_z) < 0.003, (carried_z, truth["objects"][0])  # still up
    cell.gripper.release()
