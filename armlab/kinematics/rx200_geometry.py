"""The RX200 family's planar geometry (derived from the PoX description), its closed-form FK and
the wrist-rotate choice that aligns the fingers with a block's faces.

The family: waist about the base z axis, then shoulder, elbow and wrist_angle about parallel
horizontal axes (one vertical plane, "cylindrical reduction"), then wrist_rotate about the approach
axis through the gripper point. Orientation in the base frame is Rz(q1) Ry(q2+q3+q4) Rx(q5).

Finger convention: the fingers close along the gripper frame's y axis. With wrist_rotate = 0, the
gripper pointing straight down and waist = 0 they close along the world x axis; in general, pointing
straight down, they close along the world direction at angle (waist - wrist_rotate) (mod pi).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.errors import ConfigError
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.screws import point_on_screw_axis

_TOL = 1e-9
HALF_PI = math.pi / 2.0


def wrap_angle(angle_rad: float) -> float:
    """Angle wrapped into (-pi, pi].

    >>> wrap_angle(3 * math.pi / 2) == -math.pi / 2
    True
    """
    wrapped = math.fmod(angle_rad + math.pi, 2.0 * math.pi)
    if wrapped <= 0.0:
        wrapped += 2.0 * math.pi
    return wrapped - math.pi


@dataclass(frozen=True)
class Rx200Geometry:
    """Plain-float parameters of an RX200-family arm; every length in metres, angle in radians.

    shoulder_x_m/shoulder_z_m: shoulder axis in the base frame; upper_arm_m and upper_arm_elevation_rad:
    shoulder-to-elbow vector at q = 0 (0.2062 m at 75.96 deg for the RX200); forearm_m: elbow to
    wrist_angle axis (horizontal at q = 0); tool_m: wrist_angle axis to gripper point along the approach
    axis. base_yaw_rad/base_xyz_m: T_world_base as a rotation about z and a translation.
    """

    shoulder_x_m: float
    shoulder_z_m: float
    upper_arm_m: float
    upper_arm_elevation_rad: float
    forearm_m: float
    tool_m: float
    lower_rad: tuple[float, ...]
    upper_rad: tuple[float, ...]
    base_yaw_rad: float
    base_xyz_m: tuple[float, float, float]
    joint_names: tuple[str, ...]

    @classmethod
    def from_config(cls, config: ArmConfig, source: str = "arm config") -> Rx200Geometry:
        """Derive the planar parameters from the PoX axes; ConfigError if the arm is not of this family."""
        axes = np.asarray(config.pox.screw_axes, dtype=float)
        home = np.asarray(config.pox.M, dtype=float)
        expected_w = ([0, 0, 1], [0, 1, 0], [0, 1, 0], [0, 1, 0], [1, 0, 0])
        for index, w in enumerate(expected_w):
            if not np.allclose(axes[index, :3], w, atol=1e-9):
                raise ConfigError(f"{source}: family rx200 needs pox.screw_axes[{index}] w = {w}, got {axes[index, :3]}")
        points = [point_on_screw_axis(axis) for axis in axes]
        if not (np.allclose(points[0][:2], 0.0, atol=1e-9) and all(abs(p[1]) < 1e-9 for p in points)):
            raise ConfigError(f"{source}: family rx200 needs every joint axis in the base x-z plane")
        shoulder, elbow, wrist = points[1], points[2], points[3]
        gripper = home[:3, 3]
        if not np.allclose(home[:3, :3], np.eye(3), atol=1e-9):
            raise ConfigError(f"{source}: family rx200 needs pox.M with an identity rotation (x = approach axis)")
        if abs(wrist[2] - elbow[2]) > 1e-9 or abs(gripper[2] - wrist[2]) > 1e-9 or abs(points[4][2] - gripper[2]) > 1e-9:
            raise ConfigError(f"{source}: family rx200 needs the forearm and gripper horizontal at q = 0")
        rotation = np.asarray(config.T_world_base, dtype=float)[:3, :3]
        if not np.allclose(rotation[2], [0, 0, 1], atol=1e-9):
            raise ConfigError(f"{source}: family rx200 needs T_world_base to be a rotation about z (level base)")
        upper = elbow - shoulder
        return cls(
            shoulder_x_m=float(shoulder[0]),
            shoulder_z_m=float(shoulder[2]),
            upper_arm_m=float(math.hypot(upper[0], upper[2])),
            upper_arm_elevation_rad=float(math.atan2(upper[2], upper[0])),
            forearm_m=float(wrist[0] - elbow[0]),
            tool_m=float(gripper[0] - wrist[0]),
            lower_rad=tuple(float(v) for v in np.radians(config.limits.lower_deg)),
            upper_rad=tuple(float(v) for v in np.radians(config.limits.upper_deg)),
            base_yaw_rad=float(math.atan2(rotation[1, 0], rotation[0, 0])),
            base_xyz_m=tuple(float(v) for v in np.asarray(config.T_world_base, dtype=float)[:3, 3]),
            joint_names=tuple(config.joint_names),
        )


def fk_rx200_flat(g: Rx200Geometry, q: tuple[float, ...] | list[float]) -> tuple[float, ...]:
    """World pose of the gripper point as a flat 12-tuple (3x4 row-major), plain floats (fast path)."""
    q1, q2, q3, q4, q5 = q
    e2 = g.upper_arm_elevation_rad - q2
    s3 = q2 + q3
    pitch = s3 + q4
    cp, sp = math.cos(pitch), math.sin(pitch)
    radial = g.shoulder_x_m + g.upper_arm_m * math.cos(e2) + g.forearm_m * math.cos(s3) + g.tool_m * cp
    height = g.shoulder_z_m + g.upper_arm_m * math.sin(e2) - g.forearm_m * math.sin(s3) - g.tool_m * sp
    yaw = q1 + g.base_yaw_rad
    ca, sa = math.cos(yaw), math.sin(yaw)
    cr, sr = math.cos(q5), math.sin(q5)
    bx, by, bz = g.base_xyz_m
    return (
        ca * cp, ca * sp * sr - sa * cr, ca * sp * cr + sa * sr, radial * ca + bx,
        sa * cp, sa * sp * sr + ca * cr, sa * sp * cr - ca * sr, radial * sa + by,
        -sp, cp * sr, cp * cr, height + bz,
    )  # fmt: skip


def fk_rx200_batch(g: Rx200Geometry, q: np.ndarray) -> np.ndarray:
    """World poses of the gripper point for joint vectors (N, 5) -> (N, 4, 4), vectorised."""
    q1, q2, q3, q4, q5 = np.asarray(q, dtype=float).T
    e2 = g.upper_arm_elevation_rad - q2
    s3 = q2 + q3
    pitch = s3 + q4
    cp, sp = np.cos(pitch), np.sin(pitch)
    radial = g.shoulder_x_m + g.upper_arm_m * np.cos(e2) + g.forearm_m * np.cos(s3) + g.tool_m * cp
    height = g.shoulder_z_m + g.upper_arm_m * np.sin(e2) - g.forearm_m * np.sin(s3) - g.tool_m * sp
    yaw = q1 + g.base_yaw_rad
    ca, sa = np.cos(yaw), np.sin(yaw)
    cr, sr = np.cos(q5), np.sin(q5)
    result = np.zeros((q1.shape[0], 4, 4))
    result[:, 0] = np.stack([ca * cp, ca * sp * sr - sa * cr, ca * sp * cr + sa * sr, radial * ca + g.base_xyz_m[0]], -1)
    result[:, 1] = np.stack([sa * cp, sa * sp * sr + ca * cr, sa * sp * cr - ca * sr, radial * sa + g.base_xyz_m[1]], -1)
    result[:, 2] = np.stack([-sp, cp * sr, cp * cr, height + g.base_xyz_m[2]], -1)
    result[:, 3, 3] = 1.0
    return result


def wrist_rotate_candidates(waist_rad: float, arm_pitch_rad: float, block_yaw_world_rad: float, base_yaw_rad: float) -> list[float]:
    """The four wrist_rotate angles (wrapped) that put the fingers across a block's faces.

    The fingers' closing axis (gripper y) projected on the horizontal plane is made parallel to one of
    the block's face normals (block yaw + k*pi/2). Straight down these are (waist - yaw) + k*pi/2.

    >>> sorted(round(v, 6) for v in wrist_rotate_candidates(0.0, math.pi / 2, 0.3, 0.0))
    [-1.870796, -0.3, 1.270796, 2.841593]
    """
    sin_pitch = math.sin(arm_pitch_rad)
    alpha = block_yaw_world_rad - base_yaw_rad - waist_rad
    ca, sa = math.cos(alpha), math.sin(alpha)
    # alpha + k*pi/2 has (cos, sin) = (ca, sa), (-sa, ca), (-ca, -sa), (sa, -ca)
    first = math.atan2(ca, sin_pitch * sa)
    second = math.atan2(-sa, sin_pitch * ca)
    return [wrap_angle(first), wrap_angle(second), wrap_angle(first + math.pi), wrap_angle(second + math.pi)]


def choose_wrist_rotate(
    candidates: list[float], seed_rad: float, lower_rad: float, upper_rad: float
) -> float | None:
    """The candidate (or its 2*pi shift) within limits closest to the seed; None if none fits.

    >>> choose_wrist_rotate([-1.870796, -0.3, 1.270796, 2.841593], 1.0, -math.pi, math.pi)
    1.270796
    """
    best, best_cost = None, math.inf
    two_pi = 2.0 * math.pi
    for value in candidates:
        shifted = value + two_pi * round((seed_rad - value) / two_pi)
        if not lower_rad - _TOL <= shifted <= upper_rad + _TOL:
            shifted = value  # the nearest shift is outside the limits; the wrapped value may fit
            if not lower_rad - _TOL <= shifted <= upper_rad + _TOL:
                continue
        cost = abs(shifted - seed_rad)
        if cost < best_cost:
            best, best_cost = shifted, cost
    return best


def wrist_rotate_batch(
    waist_rad: np.ndarray, arm_pitch_rad: np.ndarray, block_yaw_world_rad: np.ndarray, base_yaw_rad: float,
    seed_rad: np.ndarray, lower_rad: float, upper_rad: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised choose_wrist_rotate(wrist_rotate_candidates(...)): (N,) arrays -> (q5 (N,), ok (N,))."""
    sin_pitch = np.sin(arm_pitch_rad)
    alpha0 = block_yaw_world_rad - base_yaw_rad - waist_rad
    k = np.arange(4)[:, None]
    alpha = alpha0[None, :] + k * HALF_PI
    base = np.arctan2(np.cos(alpha), sin_pitch[None, :] * np.sin(alpha))
    options = np.concatenate([base, base - 2.0 * np.pi, base + 2.0 * np.pi], axis=0)
    fits = (options >= lower_rad - _TOL) & (options <= upper_rad + _TOL)
    cost = np.where(fits, np.abs(options - seed_rad[None, :]), np.inf)
    pick = np.argmin(cost, axis=0)
    columns = np.arange(options.shape[1])
    return options[pick, columns], np.isfinite(cost[pick, columns])


def approach_pitch_rad(T_world_gripper: np.ndarray, base_xyz_m: tuple[float, float, float]) -> float:
    """Pitch of the approach axis below the horizontal, in the vertical plane through the base axis
    and the gripper point: 0 = pointing radially outward, pi/2 = straight down, pi = back toward the base."""
    approach = np.asarray(T_world_gripper)[:3, 0]
    radial = np.asarray(T_world_gripper)[:2, 3] - np.asarray(base_xyz_m[:2])
    norm = float(np.hypot(*radial))
    horizontal = float(np.dot(approach[:2], radial / norm)) if norm > 1e-12 else float(np.hypot(*approach[:2]))
    return math.atan2(-float(approach[2]), horizontal)
