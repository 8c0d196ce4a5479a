"""Product-of-exponentials kinematics after Lynch & Park, *Modern Robotics* (ch. 3-5), snake_case.

Pure numpy functions: skew matrices, matrix exponentials and logarithms, space-frame forward
kinematics (single or batched joint vectors) and the space Jacobian. A screw axis is (w | v) with
w the unit rotation axis and v = -w x q for a point q on the axis.
"""

from __future__ import annotations

import numpy as np

_EPS = 1e-9


def near_zero(value: float) -> bool:
    """True when |value| is below 1e-9.

    >>> near_zero(-1e-12), near_zero(1e-3)
    (True, False)
    """
    return abs(value) < _EPS


def vec_to_so3(omega: np.ndarray) -> np.ndarray:
    """The 3x3 skew-symmetric matrix [w] with [w] @ x = w x x.

    >>> vec_to_so3(np.array([1.0, 2.0, 3.0])).tolist()
    [[0.0, -3.0, 2.0], [3.0, 0.0, -1.0], [-2.0, 1.0, 0.0]]
    """
    wx, wy, wz = np.asarray(omega, dtype=float)
    return np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])


def so3_to_vec(so3_matrix: np.ndarray) -> np.ndarray:
    """The 3-vector of a skew-symmetric matrix (inverse of vec_to_so3).

    >>> so3_to_vec(vec_to_so3(np.array([1.0, 2.0, 3.0]))).tolist()
    [1.0, 2.0, 3.0]
    """
    m = np.asarray(so3_matrix, dtype=float)
    return np.array([m[2, 1], m[0, 2], m[1, 0]])


def vec_to_se3(twist: np.ndarray) -> np.ndarray:
    """The 4x4 se(3) matrix [V] of a 6-vector twist (w | v).

    >>> vec_to_se3(np.array([0, 0, 1, 1, 2, 3.0]))[:3, 3].tolist()
    [1.0, 2.0, 3.0]
    """
    twist = np.asarray(twist, dtype=float)
    matrix = np.zeros((4, 4))
    matrix[:3, :3] = vec_to_so3(twist[:3])
    matrix[:3, 3] = twist[3:]
    return matrix


def se3_to_vec(se3_matrix: np.ndarray) -> np.ndarray:
    """The 6-vector twist (w | v) of a 4x4 se(3) matrix (inverse of vec_to_se3)."""
    m = np.asarray(se3_matrix, dtype=float)
    return np.array([m[2, 1], m[0, 2], m[1, 0], m[0, 3], m[1, 3], m[2, 3]])


def matrix_exp3(so3_matrix: np.ndarray) -> np.ndarray:
    """Rotation matrix exp([w] theta) by Rodrigues' formula; the input is [w] * theta.

    >>> np.round(matrix_exp3(vec_to_so3(np.array([0, 0, np.pi / 2]))), 6).tolist()
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    m = np.asarray(so3_matrix, dtype=float)
    theta = float(np.linalg.norm(so3_to_vec(m)))
    if near_zero(theta):
        return np.eye(3)
    unit = m / theta
    return np.eye(3) + np.sin(theta) * unit + (1.0 - np.cos(theta)) * (unit @ unit)


def matrix_exp6(se3_matrix: np.ndarray) -> np.ndarray:
    """Homogeneous transform exp([S] theta); the input is [S] * theta.

    Example: a unit rotation about the z axis through (1, 0, 0) by pi moves the origin to (2, 0, 0).

    >>> axis = np.array([0, 0, 1, 0, -1, 0.0])
    >>> np.round(matrix_exp6(vec_to_se3(axis) * np.pi)[:3, 3], 9).tolist()
    [2.0, 0.0, 0.0]
    """
    m = np.asarray(se3_matrix, dtype=float)
    omega_theta = so3_to_vec(m[:3, :3])
    result = np.eye(4)
    theta = float(np.linalg.norm(omega_theta))
    if near_zero(theta):
        result[:3, 3] = m[:3, 3]
        return result
    omega_mat = m[:3, :3] / theta
    result[:3, :3] = matrix_exp3(m[:3, :3])
    g = np.eye(3) * theta + (1.0 - np.cos(theta)) * omega_mat + (theta - np.sin(theta)) * (omega_mat @ omega_mat)
    result[:3, 3] = g @ (m[:3, 3] / theta)
    return result


def matrix_log3(rotation: np.ndarray) -> np.ndarray:
    """The so(3) matrix [w] theta whose exponential is `rotation` (theta in [0, pi]).

    >>> np.round(so3_to_vec(matrix_log3(matrix_exp3(vec_to_so3(np.array([0.1, -0.2, 0.3]))))), 9).tolist()
    [0.1, -0.2, 0.3]
    """
    r = np.asarray(rotation, dtype=float)
    cos_theta = (np.trace(r) - 1.0) / 2.0
    if cos_theta >= 1.0 - 1e-12:
        return np.zeros((3, 3))
    if cos_theta <= -1.0 + 1e-12:
        # theta = pi: the axis is the column of (R + I) with the largest norm.
        column = int(np.argmax(np.diag(r)))
        omega = (r[:, column] + np.eye(3)[:, column]) / np.sqrt(2.0 * (1.0 + r[column, column]))
        return vec_to_so3(np.pi * omega)
    theta = float(np.arccos(cos_theta))
    return theta / (2.0 * np.sin(theta)) * (r - r.T)


def matrix_log6(transform: np.ndarray) -> np.ndarray:
    """The se(3) matrix [S] theta whose exponential is `transform`.

    >>> T = matrix_exp6(vec_to_se3(np.array([0, 0, 1, 0, -1, 0.0]) * 0.5))
    >>> (np.round(se3_to_vec(matrix_log6(T)), 9) + 0.0).tolist()
    [0.0, 0.0, 0.5, 0.0, -0.5, 0.0]
    """
    t = np.asarray(transform, dtype=float)
    omega_mat = matrix_log3(t[:3, :3])
    result = np.zeros((4, 4))
    if np.allclose(omega_mat, 0.0):
        result[:3, 3] = t[:3, 3]
        return result
    theta = float(np.linalg.norm(so3_to_vec(omega_mat)))
    unit = omega_mat / theta
    g_inv = (
        np.eye(3) / theta
        - unit / 2.0
        + (1.0 / theta - 1.0 / np.tan(theta / 2.0) / 2.0) * (unit @ unit)
    )
    result[:3, :3] = omega_mat
    result[:3, 3] = g_inv @ t[:3, 3] * theta
    return result


def trans_inv(transform: np.ndarray) -> np.ndarray:
    """Inverse of a rigid transform without a general matrix inverse.

    >>> trans_inv(np.array([[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1.0]]))[:3, 3].tolist()
    [-1.0, -2.0, -3.0]
    """
    t = np.asarray(transform, dtype=float)
    result = np.eye(4)
    result[:3, :3] = t[:3, :3].T
    result[:3, 3] = -t[:3, :3].T @ t[:3, 3]
    return result


def adjoint(transform: np.ndarray) -> np.ndarray:
    """The 6x6 adjoint [Ad_T] mapping twists (w | v) from T's frame to its parent frame."""
    t = np.asarray(transform, dtype=float)
    rotation, position = t[:3, :3], t[:3, 3]
    result = np.zeros((6, 6))
    result[:3, :3] = rotation
    result[3:, 3:] = rotation
    result[3:, :3] = vec_to_so3(position) @ rotation
    return result


def screw_axis_from_point(omega: np.ndarray, point_m: np.ndarray) -> np.ndarray:
    """Screw axis (w | -w x q) of a revolute joint with unit axis w through point q.

    >>> screw_axis_from_point(np.array([0, 1, 0.0]), np.array([0.05, 0, 0.30457])).tolist()
    [0.0, 1.0, 0.0, -0.30457, 0.0, 0.05]
    """
    omega = np.asarray(omega, dtype=float)
    return np.concatenate([omega, -np.cross(omega, np.asarray(point_m, dtype=float))]) + 0.0


def point_on_screw_axis(screw_axis: np.ndarray) -> np.ndarray:
    """The point of a revolute screw axis closest to the origin (w x v for unit w).

    >>> point_on_screw_axis(np.array([0, 1, 0, -0.30457, 0, 0.05])).tolist()
    [0.05, 0.0, 0.30457]
    """
    axis = np.asarray(screw_axis, dtype=float)
    return np.cross(axis[:3], axis[3:]) + 0.0


def matrix_exp6_batch(screw_axis: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """exp([S] theta) for one unit revolute screw axis (6,) and N angles: (N,) -> (N, 4, 4).

    >>> np.allclose(matrix_exp6_batch(np.array([0, 0, 1, 0, -1, 0.0]), np.array([0.3]))[0],
    ...             matrix_exp6(vec_to_se3(np.array([0, 0, 1, 0, -1, 0.0]) * 0.3)))
    True
    """
    omega, v = screw_axis[:3], screw_axis[3:]
    w_mat = vec_to_so3(omega)
    w_mat2 = w_mat @ w_mat
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    result = np.zeros((theta.shape[0], 4, 4))
    result[:, :3, :3] = np.eye(3) + sin_t[:, None, None] * w_mat + (1.0 - cos_t)[:, None, None] * w_mat2
    g_v = (
        theta[:, None] * v
        + (1.0 - cos_t)[:, None] * (w_mat @ v)
        + (theta - sin_t)[:, None] * (w_mat2 @ v)
    )
    result[:, :3, 3] = g_v
    result[:, 3, 3] = 1.0
    return result


def fk_space(home: np.ndarray, screw_axes: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Space-frame forward kinematics T = exp([S1]q1) ... exp([Sn]qn) M.

    home: (4, 4) end-effector pose at q = 0; screw_axes: (n, 6) rows (w | v) in the space frame;
    q: (n,) -> (4, 4), or (N, n) -> (N, 4, 4).

    Example (the RX200's official check point, in mm):

    >>> M = np.array([[1, 0, 0, 0.408575], [0, 1, 0, 0], [0, 0, 1, 0.30457], [0, 0, 0, 1]])
    >>> S = np.array([[0, 0, 1, 0, 0, 0], [0, 1, 0, -0.10457, 0, 0], [0, 1, 0, -0.30457, 0, 0.05],
    ...               [0, 1, 0, -0.30457, 0, 0.25], [1, 0, 0, 0, 0.30457, 0]])
    >>> np.round(fk_space(M, S, np.array([0.3, -0.2, 0.4, 1.0, 0.5]))[:3, 3] * 1000, 1).tolist()
    [251.0, 77.6, 123.0]
    """
    q = np.asarray(q, dtype=float)
    axes = np.asarray(screw_axes, dtype=float)
    single = q.ndim == 1
    q_batch = q[None, :] if single else q
    result = np.broadcast_to(np.eye(4), (q_batch.shape[0], 4, 4)).copy()
    for index in range(axes.shape[0]):
        result = result @ matrix_exp6_batch(axes[index], q_batch[:, index])
    result = result @ np.asarray(home, dtype=float)
    return result[0] if single else result


def jacobian_space(screw_axes: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Space Jacobian (6, n): column i is Ad(exp([S1]q1)...exp([S_{i-1}]q_{i-1})) S_i.

    Its rows are (angular | linear) velocity of the body as a spatial twist; the linear velocity of a
    point p is v + w x p.

    >>> S = np.array([[0, 0, 1, 0, 0, 0], [0, 0, 1, 0, -1, 0.0]])
    >>> (np.round(jacobian_space(S, np.array([np.pi / 2, 0.0])), 9)[:, 1] + 0.0).tolist()
    [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]
    """
    axes = np.asarray(screw_axes, dtype=float)
    q = np.asarray(q, dtype=float)
    jacobian = axes.T.copy()
    transform = np.eye(4)
    for index in range(1, axes.shape[0]):
        transform = transform @ matrix_exp6(vec_to_se3(axes[index - 1] * q[index - 1]))
        jacobian[:, index] = adjoint(transform) @ axes[index]
    return jacobian


def rpy_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (rad) with R = Rz(yaw) Ry(pitch) Rx(roll); pitch in [-pi/2, pi/2].

    With x the approach axis, pitch is the angle of the approach axis below the horizontal.

    >>> np.round(rpy_from_rotation(np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0.0]])), 6).tolist()
    [0.0, 1.570796, 0.0]
    """
    r = np.asarray(rotation, dtype=float)
    pitch = float(np.arcsin(np.clip(-r[2, 0], -1.0, 1.0)))
    if abs(r[2, 0]) < 1.0 - 1e-9:
        roll = float(np.arctan2(r[2, 1], r[2, 2]))
        yaw = float(np.arctan2(r[1, 0], r[0, 0]))
    else:  # gimbal lock: only roll - yaw (or roll + yaw) is defined; report it as yaw
        roll = 0.0
        yaw = float(np.arctan2(-r[0, 1], r[1, 1]))
    return np.array([roll, pitch, yaw]) + 0.0
