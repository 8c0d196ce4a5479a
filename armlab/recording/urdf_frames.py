"""The arm's URDF for Foxglove and its links' transforms: what robot_state_publisher does for ROS, for the station.

station_urdf(station, mesh_url): the URDF the web page's 3-D panel draws (armlab.station.arm_urdf, one generator),
its meshes named under `mesh_url` (the live server's package://armlab/meshes/<arm>/: Foxglove fetches them from it).
UrdfFrames(urdf).transforms(positions): (parent link, child link, 4x4 pose of the child in the parent) for every
joint of the URDF at the given joint positions (radians; prismatic: metres), the fixed ones included: Foxglove's 3-D
panel places each link of the URDF by these frames (it moves a URDF by its frames only, not by joint states).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from armlab.station.arm_urdf import FINGER_JOINTS, MeshSet, arm_urdf, matrix_from_rpy, transform


def station_urdf(station: Any, mesh_url: str | None = None) -> str | None:
    """The station's arm as a URDF (None without an arm); mesh_url: where its meshes are named (default: the web
    page's /meshes/<arm>/)."""
    model = station.model
    if model is None:
        return None
    meshes = MeshSet.load(model.name)
    if meshes is not None and mesh_url is not None:
        meshes = replace(meshes, url=mesh_url)
    return arm_urdf(model.config, np.asarray(model.T_world_base), meshes)


def finger_offset_m(station: Any, width_m: float) -> float:
    """Each finger's offset from the centre line at the gripper's pad span width_m (as the web page's 3-D panel)."""
    gripper = station.model.config.gripper
    return width_m / 2.0 + (gripper.pad_thickness_m if gripper is not None else 0.0)


@dataclass(frozen=True)
class UrdfJoint:
    name: str
    kind: str  # revolute | continuous | prismatic | fixed
    parent: str
    child: str
    origin: np.ndarray  # 4x4, the child at position 0 in the parent
    axis: np.ndarray  # unit vector in the child frame


def _axis_motion(kind: str, axis: np.ndarray, position: float) -> np.ndarray:
    """One joint's motion at `position` (UrdfFrames computes all of them at once; this is the reference)."""
    if kind in ("revolute", "continuous"):
        x, y, z = axis
        c, s, t = math.cos(position), math.sin(position), 1.0 - math.cos(position)
        return transform(R=np.array([[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                                     [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                                     [t * x * z - s * y, t * y * z + s * x, t * z * z + c]]))
    if kind == "prismatic":
        return transform(axis * position)
    return np.eye(4)


class UrdfFrames:
    """The joints of a URDF (its text) and their transforms at given positions."""

    def __init__(self, urdf: str) -> None:
        self.joints: list[UrdfJoint] = []
        for element in ET.fromstring(urdf).iter("joint"):
            origin = element.find("origin")
            xyz = [float(v) for v in origin.get("xyz", "0 0 0").split()] if origin is not None else [0.0, 0.0, 0.0]
            rpy = [float(v) for v in origin.get("rpy", "0 0 0").split()] if origin is not None else [0.0, 0.0, 0.0]
            axis = element.find("axis")
            direction = np.array([float(v) for v in axis.get("xyz").split()]) if axis is not None else np.array([1.0, 0.0, 0.0])
            self.joints.append(UrdfJoint(element.get("name"), element.get("type"), element.find("parent").get("link"),
                                         element.find("child").get("link"), transform(xyz, matrix_from_rpy(rpy)),
                                         direction / np.linalg.norm(direction)))

        # a fixed joint's transform never changes: computed once (the same product as a moving joint's)
        self._fixed = [joint.origin @ np.eye(4) if joint.kind == "fixed" else None for joint in self.joints]
        # the moving ones, all at once (recorder's /tf at 30 Hz: one numpy pass instead of one small matrix per joint)
        moving = [joint for joint in self.joints if joint.kind != "fixed"]
        self._moving_names = [joint.name for joint in moving]
        self._origins = np.array([joint.origin for joint in moving]).reshape(-1, 4, 4)
        axes = np.array([joint.axis for joint in moving], dtype=float).reshape(-1, 3)
        self._axes = axes
        self._revolute = np.array([joint.kind in ("revolute", "continuous") for joint in moving], dtype=bool)
        self._outer = axes[:, :, None] * axes[:, None, :]  # a a^T
        zero = np.zeros(len(moving))
        self._skew = np.stack([np.stack([zero, -axes[:, 2], axes[:, 1]], -1), np.stack([axes[:, 2], zero, -axes[:, 0]], -1),
                               np.stack([-axes[:, 1], axes[:, 0], zero], -1)], 1)  # [a]

    @property
    def links(self) -> list[str]:
        return [joint.child for joint in self.joints]

    def transforms(self, positions: dict[str, float]) -> list[tuple[str, str, np.ndarray]]:
        """(parent, child, T_parent_child) per joint; a moving joint not in `positions` at 0. A revolute joint turns
        by R = cos I + (1 - cos) a a^T + sin [a] about its axis a, a prismatic one moves along it (_axis_motion's
        matrices, every moving joint in one pass)."""
        p = np.array([float(positions.get(name, 0.0)) for name in self._moving_names])
        cos_p, sin_p = np.cos(p), np.sin(p)
        motion = np.zeros((len(p), 4, 4))
        motion[:, 3, 3] = 1.0
        turned = (cos_p[:, None, None] * np.eye(3) + (1.0 - cos_p)[:, None, None] * self._outer + sin_p[:, None, None] * self._skew)
        motion[:, :3, :3] = np.where(self._revolute[:, None, None], turned, np.eye(3))
        motion[:, :3, 3] = np.where(self._revolute[:, None], 0.0, self._axes * p[:, None])
        moved = iter(self._origins @ motion)
        return [(joint.parent, joint.child, self._fixed[index] if self._fixed[index] is not None else next(moved))
                for index, joint in enumerate(self.joints)]


def joint_positions(names, q_rad, finger_m: float | None) -> dict[str, float]:
    """{joint name: position} for UrdfFrames.transforms: the arm's joints, and the fingers' offset when known."""
    positions = {str(name): float(q) for name, q in zip(names, q_rad)}
    if finger_m is not None:
        positions.update(dict.fromkeys(FINGER_JOINTS, float(finger_m)))
    return positions
