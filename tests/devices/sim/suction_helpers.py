"""Helpers for the UR3 suction-cup workcell tests: cup poses (approach axis down, optionally tilted),
straight Cartesian moves through the arm model's numerical IK (armlab.kinematics, independent of the
simulation's model builder), and a one-block scene on the UR3 board."""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.scene import Scene, SceneObject
from armlab.workcell import load_workcell, load_workcell_arm

WORKCELL = "ur3_suction"


def cup_pose(position_m, tilt_deg: float = 0.0, yaw_rad: float = 0.0) -> np.ndarray:
    """T_world_tool with the approach axis (tool x) straight down, then tilted tilt_deg about world x."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    down = np.array([[0.0, c, s], [0.0, s, -c], [-1.0, 0.0, 0.0]])  # columns: x = down, y = heading yaw, z = x cross y
    t = math.radians(tilt_deg)
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, math.cos(t), -math.sin(t)], [0.0, math.sin(t), math.cos(t)]])
    T = np.eye(4)
    T[:3, :3] = tilt @ down
    T[:3, 3] = position_m
    return T


def block_scene(x_m: float, y_m: float, yaw_rad: float = 0.0, block_id: str = "b1") -> Scene:
    edge = load_workcell(WORKCELL).block_edge_m("large")
    half = 0.5 * yaw_rad
    return Scene(objects=[SceneObject(id=block_id, type="block", color="yellow", size="large",
                                      position_m=(x_m, y_m, 0.5 * edge), quat_wxyz=(math.cos(half), 0.0, 0.0, math.sin(half)))])


def move_line(cell, T_start: np.ndarray, T_end: np.ndarray, duration_s: float, points: int = 25) -> None:
    """Straight-line tool motion from T_start to T_end (orientation of T_end), quintic timing; blocks until done."""
    arm = load_workcell_arm(WORKCELL)
    q = cell.arm.read_joint_state().position_rad
    path = []
    for s in np.linspace(0.0, 1.0, points):
        T = T_end.copy()
        T[:3, 3] = (1 - s) * T_start[:3, 3] + s * T_end[:3, 3]
        q = arm.ik_pose(T, q_seed=q)
        path.append(q)
    move_joints(cell, np.array(path), duration_s)


def move_joints(cell, waypoints_rad: np.ndarray, duration_s: float, smooth: bool = True, wait: bool = True) -> None:
    """Through the waypoints (first = near the current joints), 250 Hz samples: on a quintic time scale
    (smooth), or at constant speed (the speed jumps from zero at the start: a jerk no planner would send)."""
    q0 = cell.arm.read_joint_state().position_rad
    waypoints = np.vstack([q0, np.atleast_2d(waypoints_rad)])
    times = np.linspace(0.0, duration_s, max(2, int(duration_s * 250) + 1))
    s = times / duration_s
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5 if smooth else s
    u = blend * (len(waypoints) - 1)
    i = np.minimum(u.astype(int), len(waypoints) - 2)
    frac = (u - i)[:, None]
    positions = waypoints[i] * (1 - frac) + waypoints[i + 1] * frac
    cell.arm.command_trajectory(JointTrajectory(times, positions), wait=wait)


def move_to_pose(cell, T: np.ndarray, duration_s: float) -> None:
    """Joint-space move to the IK solution of T nearest the current joints."""
    arm = load_workcell_arm(WORKCELL)
    q = arm.ik_pose(T, q_seed=cell.arm.read_joint_state().position_rad)
    move_joints(cell, q, duration_s)


def object_position(cell, object_id: str) -> np.ndarray:
    return np.array(next(o for o in cell.truth()["objects"] if o["id"] == object_id)["position_m"])


def top_face_centre(cell, object_id: str) -> np.ndarray:
    """World centre of the block's top face (ground truth): where a held block meets the cup."""
    import mujoco

    obj = next(o for o in cell.truth()["objects"] if o["id"] == object_id)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(obj["quat_wxyz"], dtype=float))
    edge = load_workcell(WORKCELL).block_edge_m("large")
    return np.asarray(obj["position_m"]) + R.reshape(3, 3) @ np.array([0.0, 0.0, 0.5 * edge])
