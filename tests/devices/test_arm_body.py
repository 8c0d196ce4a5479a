"""One geometry of the arm (issue 20 item 4): the arm body (armlab.devices.arm_body) placed by the arm model's
joint frames coincides, part for part, with the simulated arm's geoms as MuJoCo places them (the simulation
builds its arm from the body), for random joint vectors within the limits and random finger openings."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from armlab.devices.arm_body import arm_body, body_of, load_arm_body
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.config import load_sim_config
from armlab.kinematics import load_arm
from armlab.workcell import load_workcell_arm

UR3_WORKCELL = "ur3_suction"
SHAPES = {"capsule": mujoco.mjtGeom.mjGEOM_CAPSULE, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
          "box": mujoco.mjtGeom.mjGEOM_BOX}


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(realtime=False, realism="ideal")) as workcell:
        yield workcell


@pytest.fixture(scope="module")
def ur3_cell():
    with SimWorkcell(SimWorkcellConfig(workcell=UR3_WORKCELL, realtime=False, camera_pose_error=False)) as workcell:
        yield workcell


def assert_sim_is_body(model, arm, body, fingers: bool, seed: int) -> None:
    """For random joints within the limits (and finger openings), every part of the body placed by the arm model
    is the simulated geom of its name: shape, size, centre and axes as MuJoCo's forward kinematics puts it."""
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(arm.lower_rad, -np.pi), np.minimum(arm.upper_rad, np.pi)
    for _ in range(25):
        q = rng.uniform(lo, hi)
        finger_m = rng.uniform(body.finger_offset_max_m * 0.4, body.finger_offset_max_m) if fingers else None
        for name, value in zip(arm.joint_names, q):
            data.qpos[model.joint(name).qposadr[0]] = value
        for side in ("left", "right") if fingers else ():
            data.qpos[model.joint(f"{side}_finger").qposadr[0]] = finger_m
        mujoco.mj_kinematics(model, data)
        placed = body.place(arm, q, finger_offset_m=finger_m)
        for k, part in enumerate(body.parts):
            if part.name == "cup_body":
                continue  # the simulated cup ends short of its lip, a ring of contact spheres (mjcf_dh)
            geom = model.geom(part.name)
            assert geom.type[0] == SHAPES[part.shape], part.name
            size = part.size_m if part.shape == "box" else part.size_m[:2]
            np.testing.assert_allclose(geom.size[: len(size)], size, atol=1e-9, err_msg=part.name)
            np.testing.assert_allclose(data.geom_xpos[geom.id], placed.poses[0, k, :3, 3], atol=1e-6, err_msg=part.name)
            R = data.geom_xmat[geom.id].reshape(3, 3)
            axes = [2] if part.shape != "box" else [0, 1, 2]  # a capsule or cylinder may turn about its own axis
            for a in axes:
                assert abs(abs(R[:, a] @ placed.poses[0, k, :3, a]) - 1.0) < 1e-6, (part.name, a)


def test_the_simulated_rx200_is_the_arm_body_at_random_joints(cell):
    body = load_arm_body("rx200")
    assert {part.shape for part in body.parts} == set(SHAPES) and len(body.parts) >= 8
    assert_sim_is_body(cell._model, load_arm("rx200"), body, fingers=True, seed=20)


def test_the_simulated_ur3_is_the_arm_body_at_random_joints(ur3_cell):
    """The UR3's file has no link radii; the simulation gives its links config/sim.yaml's and builds them by the
    same description, placed by the DH frames (on the workcell's base pose)."""
    arm = load_workcell_arm(UR3_WORKCELL)
    radii = load_sim_config().servos("ur3").link_radius_m
    body = arm_body(arm.config.model_copy(update={"link_radii_m": list(radii)}))
    assert sum(part.shape == "capsule" for part in body.parts) >= 6
    assert_sim_is_body(ur3_cell._model, arm, body, fingers=False, seed=21)


def test_the_body_a_ur3_model_gives_its_users_is_the_simulated_one(ur3_cell):
    """What the self-filter, the planning checks and the side grasp read (body_of the station's model) is the body the
    simulation builds, links included: with only the cup (the UR3's file has no link radii) the self-filter left the
    UR3's links in the depth, and the standing arm was detected as a 423 mm stack at its base (the browser's reach
    state over 'the first block' said out of reach)."""
    arm = load_workcell_arm(UR3_WORKCELL)
    assert sum(part.shape == "capsule" for part in body_of(arm).parts) >= 6
    assert_sim_is_body(ur3_cell._model, arm, body_of(arm), fingers=False, seed=22)


def test_every_simulated_arm_geom_that_collides_is_a_part_of_the_body(cell):
    model = cell._model
    names = {part.name for part in load_arm_body("rx200").parts}
    arm_bodies = {model.body(name).id for name in ("base", "waist_link", "shoulder_link", "forearm_link", "wrist_link",
                                                   "gripper_link", "left_finger", "right_finger")}
    colliding = {model.geom(g).name for g in range(model.ngeom)
                 if model.geom_bodyid[g] in arm_bodies and model.geom_contype[g] | model.geom_conaffinity[g]}
    assert colliding == names


def test_a_dh_arm_has_its_links_and_cup_in_the_right_frames():
    """The UR3 (a DH table, no link radii in its file: links as lines) has its cup on the tool frame, along the
    approach axis behind the tool point."""
    arm, body = load_arm("ur3"), load_arm_body("ur3")
    placed = body.place(arm, arm.home_rad)
    (cup,) = [k for k, part in enumerate(body.parts) if part.name == "cup_body"]
    tool = np.asarray(arm.fk(arm.home_rad))
    axis = placed.poses[0, cup, :3, 2]
    assert abs(abs(axis @ tool[:3, 0]) - 1.0) < 1e-9
    centre_along = (placed.poses[0, cup, :3, 3] - tool[:3, 3]) @ tool[:3, 0]
    assert centre_along == pytest.approx(-0.5 * arm.config.suction_cup.body_length_m)
