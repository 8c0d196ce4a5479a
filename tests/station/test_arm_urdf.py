"""The 3-D panel's URDF (armlab.station.arm_urdf) is the arm the station computes with: its tool_point link,
posed by the URDF's own joints at random joint angles, is the arm model's FK (RX200 from its urdf_origins,
UR3 from its DH table, with and without the vendor's meshes); the mesh files it names exist, and the fingers
slide by the finger offset."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from armlab.devices.arm_body import body_of
from armlab.station.arm_urdf import TOOL_LINK, MeshSet, arm_urdf, matrix_from_rpy, part_links, transform
from armlab.workcell import load_workcell_arm

REPO_WEB = __import__("pathlib").Path(__file__).resolve().parents[2] / "web"


def _axis_rotation(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def urdf_link_poses(urdf: str, values: dict[str, float]) -> dict[str, np.ndarray]:
    """World pose of every link (root 'world') with the joints at `values` (radians / metres, 0 if absent)."""
    root = ET.fromstring(urdf)
    poses = {"world": np.eye(4)}
    joints = root.findall("joint")
    while len(poses) < len(joints) + 1:
        for joint in joints:
            parent, child = joint.find("parent").get("link"), joint.find("child").get("link")
            if parent not in poses or child in poses:
                continue
            origin = joint.find("origin")
            T = transform([float(v) for v in origin.get("xyz").split()],
                          matrix_from_rpy([float(v) for v in origin.get("rpy").split()]))
            axis_node = joint.find("axis")
            value = values.get(joint.get("name"), 0.0)
            if joint.get("type") == "revolute":
                T = T @ transform(R=_axis_rotation([float(v) for v in axis_node.get("xyz").split()], value))
            elif joint.get("type") == "prismatic":
                T = T @ transform(value * np.asarray([float(v) for v in axis_node.get("xyz").split()]))
            poses[child] = poses[parent] @ T
    return poses


@pytest.mark.parametrize("workcell", ["rx200_armlab", "ur3_suction"])
@pytest.mark.parametrize("with_meshes", [True, False])
def test_the_urdf_tool_point_is_the_models_fk(workcell, with_meshes):
    model = load_workcell_arm(workcell)
    meshes = MeshSet.load(model.name) if with_meshes else None
    assert (meshes is not None) == with_meshes
    urdf = arm_urdf(model.config, np.asarray(model.T_world_base), meshes)
    rng = np.random.default_rng(7)
    for _ in range(20):
        q = rng.uniform(np.maximum(model.lower_rad, -math.pi), np.minimum(model.upper_rad, math.pi))
        poses = urdf_link_poses(urdf, dict(zip(model.joint_names, q.tolist())))
        expected = model.fk(q)
        assert np.allclose(poses[TOOL_LINK][:3, 3], expected[:3, 3], atol=1e-6), (q, poses[TOOL_LINK], expected)
        assert np.allclose(poses[TOOL_LINK][:3, :3], expected[:3, :3], atol=1e-6)


@pytest.mark.parametrize("arm", ["rx200", "ur3"])
def test_the_mesh_files_named_exist_with_their_licence(arm):
    meshes = MeshSet.load(arm)
    model = load_workcell_arm("rx200_armlab" if arm == "rx200" else "ur3_suction")
    urdf = arm_urdf(model.config, np.asarray(model.T_world_base), meshes)
    files = [node.get("filename") for node in ET.fromstring(urdf).iter("mesh")]
    assert len(files) == len(meshes.visuals) >= 7
    for url in files:
        assert (REPO_WEB / url.lstrip("/")).is_file(), url
    assert "BSD" in (REPO_WEB / meshes.url.strip("/") / "LICENSE").read_text() or "Redistribution" in (
        REPO_WEB / meshes.url.strip("/") / "LICENSE").read_text()


def test_the_fingers_slide_by_the_finger_offset():
    model = load_workcell_arm("rx200_armlab")
    urdf = arm_urdf(model.config, np.asarray(model.T_world_base), MeshSet.load("rx200"))
    q = dict(zip(model.joint_names, [0.3, -0.2, 0.1, 0.4, 0.5]))
    closed = urdf_link_poses(urdf, q | {"left_finger": 0.015, "right_finger": 0.015})
    opened = urdf_link_poses(urdf, q | {"left_finger": 0.037, "right_finger": 0.037})
    span = lambda p: np.linalg.norm(p["left_finger_link"][:3, 3] - p["right_finger_link"][:3, 3])  # noqa: E731
    assert span(closed) == pytest.approx(0.030, abs=1e-9) and span(opened) == pytest.approx(0.074, abs=1e-9)


@pytest.mark.parametrize("workcell", ["rx200_armlab", "ur3_suction"])
@pytest.mark.parametrize("with_meshes", [True, False])
def test_every_part_a_refusal_names_is_drawn_by_links_of_the_urdf(workcell, with_meshes):
    """A refused plan's part (UnsafeTrajectory.part: a joint, a joint's origin, the gripper's parts) is shown red
    in the 3-D panel through part_links: each names links of this URDF that carry something to draw, and the
    gripper's parts name the links that carry the fingers or the cup."""
    model = load_workcell_arm(workcell)
    urdf = arm_urdf(model.config, np.asarray(model.T_world_base), MeshSet.load(model.name) if with_meshes else None)
    drawn = {link.get("name") for link in ET.fromstring(urdf).iter("link") if link.find("visual") is not None}
    links = part_links(model.config)
    names = list(model.joint_names)
    parts = names + [f"{name} origin" for name in names] + ["gripper point", "finger tips", "fingers", "palm", "held block"]
    assert set(parts) <= set(links)
    for part in parts:
        assert links[part] and set(links[part]) <= drawn, (part, links[part], drawn)
    tool = {"left_finger_link", "right_finger_link"} if model.config.gripper is not None else {TOOL_LINK}
    assert set(links["fingers"]) == tool and tool <= set(links["gripper point"])
    assert links[names[1]] == [f"{names[1]}_link"]  # a joint at its limit: the link it turns


@pytest.mark.parametrize("workcell", ["rx200_armlab", "ur3_suction"])
@pytest.mark.parametrize("with_meshes", [True, False])
def test_the_urdf_collision_shapes_are_the_arm_body_where_the_model_puts_it(workcell, with_meshes):
    """Every part of the arm's body (armlab.devices.arm_body: what the simulation builds and the checks use) is a
    collision shape of the URDF named after it, and posed by the URDF's joints at random joints and finger offsets
    it is where the arm model puts the body; without meshes the same shapes are what the panel draws."""
    model = load_workcell_arm(workcell)
    meshes = MeshSet.load(model.name) if with_meshes else None
    urdf = arm_urdf(model.config, np.asarray(model.T_world_base), meshes)
    body = body_of(model)
    root = ET.fromstring(urdf)
    shapes = {}  # part name -> (link, first origin)
    for link in root.iter("link"):
        for collision in link.iter("collision"):
            origin = collision.find("origin")
            shapes.setdefault(collision.get("name"), (link.get("name"), transform(
                [float(v) for v in origin.get("xyz").split()], matrix_from_rpy([float(v) for v in origin.get("rpy").split()]))))
            if not with_meshes:
                assert link.find("visual") is not None
    assert set(shapes) == {part.name for part in body.parts} and shapes
    rng = np.random.default_rng(9)
    for _ in range(10):
        q = rng.uniform(np.maximum(model.lower_rad, -math.pi), np.minimum(model.upper_rad, math.pi))
        offset = rng.uniform(0.016, 0.037) if model.config.gripper is not None else None
        fingers = {} if offset is None else {"left_finger": offset, "right_finger": offset}
        poses = urdf_link_poses(urdf, dict(zip(model.joint_names, q.tolist())) | fingers)
        placed = body.place(model, q, finger_offset_m=offset)
        for k, part in enumerate(placed.parts):
            link, T = shapes[part.name]
            np.testing.assert_allclose(poses[link] @ T, placed.poses[0, k], atol=1e-6, err_msg=part.name)
