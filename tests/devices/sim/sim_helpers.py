"""Test helpers for driving the simulated arm: a small closed-form top-down IK for the RX200 (from
DESIGN §4, independent of armlab.kinematics so the physics tests do not depend on it) and smooth
joint-space moves."""

from __future__ import annotations

import math

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell

SHOULDER_HEIGHT_M = 0.10457
UPPER_ARM = (0.05, 0.2)
FOREARM_M = 0.2


def _wrist_to_point_m() -> float:
    """wrist_angle joint -> gripper point along the gripper axis, from config/arms/rx200.yaml."""
    from armlab.devices.sim.mjcf import ArmGeometry

    origins = ArmGeometry.load("rx200").origins_m
    return origins["wrist_rotate"][0] + origins["gripper_point"][0]


WRIST_TO_POINT_M = _wrist_to_point_m()


def topdown_ik(position_m, block_yaw_rad: float = 0.0, wrist_seed_rad: float = 0.0) -> np.ndarray:
    """Joints putting the gripper point at position_m (world) pointing straight down, with the fingers
    closing across the block's faces (wrist_rotate chosen modulo 90 degrees nearest wrist_seed_rad)."""
    x, y, z = position_m
    xb, yb = y, -x  # world -> Interbotix base frame (T_world_base: world_x = -base_y, world_y = base_x)
    waist = math.atan2(yb, xb)
    r = math.hypot(xb, yb)
    dx, dz = r, z + WRIST_TO_POINT_M - SHOULDER_HEIGHT_M
    l1 = math.hypot(*UPPER_ARM)
    alpha0 = math.atan2(UPPER_ARM[1], UPPER_ARM[0])
    cos_delta = (dx * dx + dz * dz - l1 * l1 - FOREARM_M**2) / (2 * l1 * FOREARM_M)
    if abs(cos_delta) > 1:
        raise ValueError(f"unreachable top-down target {position_m}")
    delta = math.acos(cos_delta)
    e1 = math.atan2(dz, dx) + math.atan2(FOREARM_M * math.sin(delta), l1 + FOREARM_M * math.cos(delta))
    q2 = alpha0 - e1
    q3 = -(e1 - delta) - q2
    q4 = math.pi / 2 - q2 - q3
    # Pointing down, the finger axis (gripper y) lies along world heading waist + 90 deg - wrist_rotate... find
    # the wrist_rotate that aligns it with the block's x or y axis.
    finger_heading = waist + math.pi / 2 + math.pi / 2  # heading of gripper +y at wrist_rotate = 0
    q5 = finger_heading - block_yaw_rad
    q5 = wrist_seed_rad + (q5 - wrist_seed_rad + math.pi / 4) % (math.pi / 2) - math.pi / 4
    return np.array([waist, q2, q3, q4, q5])


def move(cell: SimWorkcell, q_target, duration_s: float | None = None, speed_rad_s: float = 1.0) -> None:
    """Smooth (quintic) joint move from the current position, 100 Hz samples; blocks until done."""
    q0 = cell.arm.read_joint_state().position_rad
    q1 = np.asarray(q_target, dtype=float)
    if duration_s is None:
        duration_s = max(0.3, float(np.max(np.abs(q1 - q0))) / speed_rad_s * 1.9)
    times = np.linspace(0.0, duration_s, max(2, int(duration_s * 100) + 1))
    s = times / duration_s
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    positions = q0 + np.outer(blend, q1 - q0)
    cell.arm.command_trajectory(JointTrajectory(times, positions), wait=True)


def move_to(cell: SimWorkcell, position_m, yaw_rad: float = 0.0, **kwargs) -> None:
    """Top-down move keeping the wrist continuous (no 90-degree flips while holding a block)."""
    current = cell.arm.read_joint_state().position_rad
    seed = float(np.clip(current[4], -math.pi / 2, math.pi / 2))
    move(cell, topdown_ik(position_m, yaw_rad, seed), **kwargs)


def level_ik(reach_m: float, height_m: float) -> np.ndarray:
    """Joints putting the gripper point at reach_m straight ahead of the base (waist 0: world +y) and height_m,
    the gripper level (pointing away from the base), elbow up."""
    l1 = math.hypot(*UPPER_ARM)
    alpha0 = math.atan2(UPPER_ARM[1], UPPER_ARM[0])
    dx, dz = reach_m - WRIST_TO_POINT_M, height_m - SHOULDER_HEIGHT_M
    cos_delta = (dx * dx + dz * dz - l1 * l1 - FOREARM_M**2) / (2 * l1 * FOREARM_M)
    if abs(cos_delta) > 1:
        raise ValueError(f"unreachable level target at reach {reach_m} m, height {height_m} m")
    delta = math.acos(cos_delta)
    e1 = math.atan2(dz, dx) + math.atan2(FOREARM_M * math.sin(delta), l1 + FOREARM_M * math.cos(delta))
    q2 = alpha0 - e1
    q3 = -(e1 - delta) - q2
    return np.array([0.0, q2, q3, -q2 - q3, 0.0])


def planar_fk(q) -> tuple[float, float]:
    """(reach, height) of the gripper point of the nominal RX200 at joints q (waist ignored): the inverse of
    level_ik, for any wrist angle. Positive shoulder, elbow and wrist angles pitch forward and down."""
    def turn(a, x, z):
        return x * math.cos(a) + z * math.sin(a), -x * math.sin(a) + z * math.cos(a)

    _, q2, q3, q4, _ = (float(v) for v in q)
    x, z = turn(q2, *UPPER_ARM)
    fx, fz = turn(q2 + q3, FOREARM_M, 0.0)
    gx, gz = turn(q2 + q3 + q4, WRIST_TO_POINT_M, 0.0)
    return x + fx + gx, SHOULDER_HEIGHT_M + z + fz + gz
