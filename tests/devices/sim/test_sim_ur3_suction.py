"""The UR3 suction-cup workcell in the simulation (issue 12 items 2-3), against ground truth: the simulated
arm's tool point agrees with the kinematics library's FK; the suction cup lifts a block only when its lip
seals flat on a face near the centre, carries it (the block follows the cup), and loses it when moved too
fast for the seal. Starting errors for arms and grippers that do not fit."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import yaml

from armlab.devices.gripper import Gripper
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.errors import ConfigError
from armlab.kinematics import load_arm
from armlab.workcell import load_workcell, load_workcell_arm
from suction_helpers import (
    WORKCELL,
    block_scene,
    cup_pose,
    move_joints,
    move_line,
    move_to_pose,
    object_position,
    top_face_centre,
)

BLOCK_XY = (0.0, 0.30)
EDGE_M = load_workcell(WORKCELL).block_edge_m("large")
LIP_RADIUS_M = load_arm("ur3").config.suction_cup.lip_radius_m
LIFT_Z_M = 0.15


@pytest.fixture
def ur3_cell():
    cell = SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, seed=0, camera_pose_error=False),
                       scene=block_scene(*BLOCK_XY))
    cell.start()
    yield cell
    cell.close()


def test_simulated_ur3_tool_point_matches_the_kinematics_fk_over_1000_joint_vectors(ur3_cell):
    model, data = ur3_cell.model, mujoco.MjData(ur3_cell.model)
    arm = load_workcell_arm(WORKCELL)
    # the workcell's base pose on the board times the arm file's FK (the library's reference model)
    T_world_base = load_workcell(WORKCELL).arm_base.T_world_base
    rng = np.random.default_rng(12)
    q = rng.uniform(arm.lower_rad, arm.upper_rad, size=(1000, arm.dof))
    expected = T_world_base @ load_arm("ur3").fk(q)
    qpos = [model.jnt_qposadr[model.joint(name).id] for name in arm.joint_names]
    site = model.site("gripper_point").id
    position_error, angle_error = [], []
    for qi, T in zip(q, expected):
        data.qpos[qpos] = qi
        mujoco.mj_kinematics(model, data)
        position_error.append(np.linalg.norm(data.site_xpos[site] - T[:3, 3]))
        R = data.site_xmat[site].reshape(3, 3)
        angle_error.append(math.acos(np.clip((np.trace(R.T @ T[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)))
    assert max(position_error) < 0.0005, f"max tool point error {max(position_error) * 1000:.4f} mm"
    assert max(angle_error) < math.radians(0.05), f"max tool orientation error {math.degrees(max(angle_error)):.4f} deg"


def test_ur3_workcell_builds_the_ur3_with_real_limits_a_cup_and_the_overhead_camera(ur3_cell):
    model = ur3_cell.model
    arm = load_arm("ur3")
    assert isinstance(ur3_cell.gripper, Gripper) and ur3_cell.arm.joint_names == arm.joint_names
    for i, name in enumerate(arm.joint_names):
        assert np.allclose(model.jnt_range[model.joint(name).id], [arm.lower_rad[i], arm.upper_rad[i]])
        v = arm.velocity_limit_rad_s[i]
        assert np.allclose(model.actuator_ctrlrange[model.actuator(f"{name}_vel").id], [-v, v])
    assert model.actuator("suction").dyntype == mujoco.mjtDyn.mjDYN_NONE
    assert model.actuator_trntype[model.actuator("suction").id] == mujoco.mjtTrn.mjTRN_BODY  # adhesion on the cup body
    # the overhead camera (at the workcell's mount) sees the whole larger board: every corner and tag
    # projects inside the image, and the rendered depth there is the distance to the board
    truth = ur3_cell.truth()["camera"]
    K, T_camera_world = np.asarray(truth["K"]), np.linalg.inv(np.asarray(truth["T_world_camera"]))
    workcell = load_workcell(WORKCELL)
    assert truth["T_world_camera"][2][3] == pytest.approx(workcell.camera.mount.position_m[2])
    images = ur3_cell.render_raw()
    points = [(x, y) for x, y in workcell.board.corners_m] + list(workcell.board_tags.centres_m.values())
    for x, y in points:
        p = T_camera_world @ np.array([x, y, 0.0, 1.0])
        u, v = (K @ (p[:3] / p[2]))[:2]
        assert 20 <= u <= truth["width"] - 20 and 20 <= v <= truth["height"] - 20, f"board point {(x, y)} out of view"
        assert images.depth_m[int(v), int(u)] == pytest.approx(p[2], abs=0.01)


def _pick(cell, dx_m: float = 0.0, tilt_deg: float = 0.0, press_m: float = 0.001) -> dict:
    """Descend over the block (cup centre dx_m off its centre, tilted tilt_deg with the lowest lip point
    pressing press_m into the top face), vacuum on, lift; ground truth before and after."""
    x, y = BLOCK_XY
    top = EDGE_M - press_m + LIP_RADIUS_M * math.sin(math.radians(abs(tilt_deg)))
    above, at = cup_pose([x + dx_m, y, top + 0.10], tilt_deg), cup_pose([x + dx_m, y, top], tilt_deg)
    move_to_pose(cell, above, 2.0)
    move_line(cell, above, at, 1.0)
    cell.gripper.grasp()
    grasped = cell.gripper.read_state()
    move_line(cell, at, cup_pose([x + dx_m, y, LIFT_Z_M], tilt_deg), 1.0)
    cell.step(0.3)
    return {"holding_at_grasp": grasped.holding, "state": cell.gripper.read_state(), "truth": cell.truth()["gripper"],
            "block_z": object_position(cell, "b1")[2]}


def test_flat_centred_cup_lifts_the_block_and_carries_it_along(ur3_cell):
    result = _pick(ur3_cell)
    assert result["holding_at_grasp"] and result["state"].holding and result["truth"]["holding_id"] == "b1"
    assert result["block_z"] > LIFT_Z_M - EDGE_M / 2 - 0.005  # lifted with the cup (was 0.019 on the board)
    # carry it 0.3 m sideways on a smooth move: the top face stays at the cup's lip all along
    arm = load_workcell_arm(WORKCELL)
    target = arm.ik_pose(cup_pose([0.25, 0.15, LIFT_Z_M]), q_seed=ur3_cell.arm.read_joint_state().position_rad)
    move_joints(ur3_cell, target, 2.0, wait=False)
    gaps = []
    for _ in range(25):
        ur3_cell.step(0.1)
        gaps.append(np.linalg.norm(top_face_centre(ur3_cell, "b1") - ur3_cell.gripper_point_m()))
    assert max(gaps) < 0.003, f"block top face strayed {max(gaps) * 1000:.1f} mm from the cup"
    # vent: the block drops onto the board beneath
    ur3_cell.gripper.release()
    ur3_cell.step(1.0)
    assert not ur3_cell.gripper.read_state().holding
    assert object_position(ur3_cell, "b1")[2] < EDGE_M / 2 + 0.01


def test_cup_on_the_edge_does_not_lift(ur3_cell):
    result = _pick(ur3_cell, dx_m=EDGE_M / 2)
    assert "b1" in result["truth"]["lip_contacts"] or not result["holding_at_grasp"]  # touched, yet no seal
    assert not result["holding_at_grasp"] and not result["state"].holding and result["truth"]["holding_id"] is None
    assert result["block_z"] < EDGE_M / 2 + 0.005


@pytest.mark.parametrize(("dx_m", "lifted"), [(0.006, True), (0.013, False)])
def test_the_whole_lip_must_rest_on_the_face(ur3_cell, dx_m, lifted):
    # a 38 mm block and a 9 mm lip radius: 6 mm off centre the lip is on the face; 13 mm off, part of it
    # hangs 3 mm beyond the edge (within the lip's compliance of the edge, yet no face beneath it)
    result = _pick(ur3_cell, dx_m=dx_m)
    assert result["state"].holding is lifted
    assert bool(result["block_z"] > 0.1) is lifted


def test_cup_beside_the_block_picks_nothing(ur3_cell):
    result = _pick(ur3_cell, dx_m=0.06)
    assert not result["state"].holding and result["truth"]["lip_contacts"] == []
    assert result["block_z"] < EDGE_M / 2 + 0.005


@pytest.mark.parametrize(("tilt_deg", "lifted"), [(5.0, True), (15.0, False)])
def test_tilted_cup_seals_within_the_lip_compliance_only(ur3_cell, tilt_deg, lifted):
    result = _pick(ur3_cell, tilt_deg=tilt_deg)
    assert result["state"].holding is lifted
    assert bool(result["block_z"] > 0.1) is lifted


@pytest.mark.parametrize(("smooth", "duration_s", "kept"), [(True, 2.0, True), (False, 0.35, False)])
def test_a_move_too_fast_for_the_seal_loses_the_block(ur3_cell, smooth, duration_s, kept):
    assert _pick(ur3_cell)["state"].holding
    q = ur3_cell.arm.read_joint_state().position_rad.copy()
    q[0] += 1.0  # swing the shoulder pan by 1 rad: smooth (quintic) or with a step in speed
    move_joints(ur3_cell, q, duration_s, smooth=smooth)
    ur3_cell.step(1.0)
    gap = np.linalg.norm(top_face_centre(ur3_cell, "b1") - ur3_cell.gripper_point_m())
    assert ur3_cell.gripper.read_state().holding is kept
    assert bool(gap < 0.003) is kept, f"block {gap * 1000:.1f} mm from the cup"
    assert (ur3_cell.gripper.seal_breaks == 0) is kept


def test_workcell_decides_the_arm_and_refuses_misfits(tmp_path, monkeypatch):
    with pytest.raises(ConfigError, match="contradicts workcell 'ur3_suction'"):
        SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, arm="rx200"))
    with pytest.raises(ConfigError, match="unknown workcell 'nope'.*rx200_armlab.*ur3_suction"):
        SimWorkcell(SimWorkcellConfig(workcell="nope"))
    source = load_workcell(WORKCELL)
    data = yaml.safe_load(open("config/workcells/ur3_suction.yaml"))
    data["gripper"]["type"] = "fingers"
    fingers = tmp_path / "ur3_fingers.yaml"
    fingers.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match=r"gripper.type: 'fingers' needs a finger width range.*ur3.yaml has no `gripper:`"):
        SimWorkcell(SimWorkcellConfig(workcell=str(fingers)))
    rx_data = yaml.safe_load(open("config/workcells/rx200_armlab.yaml"))
    rx_data["gripper"]["type"] = "suction"
    suction = tmp_path / "rx200_suction.yaml"
    suction.write_text(yaml.safe_dump(rx_data))
    with pytest.raises(ConfigError, match=r"gripper.type: 'suction' needs a suction cup.*rx200.yaml has no `suction_cup:`"):
        load_workcell_arm(str(suction))
    assert source.arm == "ur3" and source.gripper.type == "suction"
