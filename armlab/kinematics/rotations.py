"""Rotations, through one library (scipy's Rotation): axis-angle and rotation vectors to matrices, the angle between
two orientations, the rotation taking one direction onto another, the yaw quaternions of the scene and the
simulator, URDF's roll-pitch-yaw and the recordings' quaternions. Quaternions are (w, x, y, z), MuJoCo's order, except
quat_xyzw_from_matrix (ROS / Foxglove's); the kinematics' own screw exponentials
(screws.matrix_exp3) stay in the Modern Robotics formulation they implement."""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.spatial.transform import Rotation

X_AXIS = np.array([1.0, 0.0, 0.0])


def rotation_from_rotvec(rotvec_rad) -> np.ndarray:
    """The rotation matrix (3, 3) of a rotation vector (axis times angle, radians), or (N, 3, 3) of (N, 3)."""
    return Rotation.from_rotvec(np.asarray(rotvec_rad, dtype=float)).as_matrix()


def rotation_about(axis, angle_rad) -> np.ndarray:
    """Rotation by angle_rad about `axis` (any length but zero): (3, 3) for one angle, (N, 3, 3) for N angles."""
    unit = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    angles = np.asarray(angle_rad, dtype=float)
    return rotation_from_rotvec(unit * angles if angles.ndim == 0 else np.outer(angles, unit))


def rotation_angle_rad(R_a, R_b) -> float:
    """Angle of the rotation taking orientation R_a to R_b (0 .. pi)."""
    relative = np.asarray(R_a, dtype=float).T @ np.asarray(R_b, dtype=float)
    return float(Rotation.from_matrix(relative).magnitude())


def rotation_taking(direction_from, direction_to) -> np.ndarray:
    """The smallest rotation (3, 3) that turns the direction `direction_from` onto `direction_to`."""
    unit_from = np.asarray(direction_from, dtype=float) / np.linalg.norm(direction_from)
    unit_to = np.asarray(direction_to, dtype=float) / np.linalg.norm(direction_to)
    rotation, _ = Rotation.align_vectors(unit_to[None, :], unit_from[None, :])
    return rotation.as_matrix()


def quat_wxyz_from_matrix(R) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix."""
    return Rotation.from_matrix(np.asarray(R, dtype=float)).as_quat(scalar_first=True)


def quat_wxyz_from_yaw(yaw_rad: float) -> tuple[float, float, float, float]:
    """Quaternion (w, x, y, z) of a rotation by yaw_rad about world z."""
    w, x, y, z = Rotation.from_euler("z", float(yaw_rad)).as_quat(scalar_first=True)
    return float(w), float(x), float(y), float(z)


def yaw_from_quat_wxyz(quat_wxyz) -> float:
    """Heading of the body's x axis projected on the board (world xy), radians in (-pi, pi]."""
    x_world = Rotation.from_quat(np.asarray(quat_wxyz, dtype=float), scalar_first=True).apply(X_AXIS)
    return math.atan2(float(x_world[1]), float(x_world[0]))


def quat_xyzw_from_matrix(R) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) of a rotation matrix (the first 3 x 3 of R), as Python floats (ROS / Foxglove order)."""
    x, y, z, w = Rotation.from_matrix(np.asarray(R, dtype=float)[:3, :3]).as_quat()
    return float(x), float(y), float(z), float(w)


def matrix_from_rpy(rpy_rad) -> np.ndarray:
    """The rotation R = Rz(yaw) Ry(pitch) Rx(roll) of (roll, pitch, yaw) (URDF's fixed-axis order)."""
    return Rotation.from_euler("xyz", np.asarray(rpy_rad, dtype=float)).as_matrix()


def rpy_from_matrix(R) -> tuple[float, float, float]:
    """(roll, pitch, yaw) with R = Rz(yaw) Ry(pitch) Rx(roll); at pitch +-90 deg (gimbal lock) one of the equivalent
    triples (the rotation is what matters)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # scipy's "Gimbal lock detected": the triple is still exact
        roll, pitch, yaw = Rotation.from_matrix(np.asarray(R, dtype=float)[:3, :3]).as_euler("xyz")
    return float(roll), float(pitch), float(yaw)
