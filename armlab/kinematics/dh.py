"""Standard Denavit-Hartenberg forward kinematics (numpy, batched) and a plain-float chain for IK.

A DH row is (theta_offset_rad, d_m, a_m, alpha_rad, joint_sign): joint i contributes
Rz(sign*q_i + theta_offset) Tz(d) Tx(a) Rx(alpha). A fixed `tool` transform maps the last DH frame
to the gripper-point frame. All frames are in the arm's base frame.
"""

from __future__ import annotations

import math

import numpy as np


def dh_transform(theta_rad, d_m, a_m, alpha_rad) -> np.ndarray:
    """The standard DH link transform Rz(theta) Tz(d) Tx(a) Rx(alpha); broadcasts over arrays.

    Scalars give (4, 4); arrays of shape (N,) give (N, 4, 4).

    >>> np.round(dh_transform(np.pi / 2, 0.1, 0.2, 0.0), 9)[:3, 3].tolist()
    [0.0, 0.2, 0.1]
    """
    theta, d, a, alpha = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (theta_rad, d_m, a_m, alpha_rad)))
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    result = np.zeros(theta.shape + (4, 4))
    result[..., 0, 0] = ct
    result[..., 0, 1] = -st * ca
    result[..., 0, 2] = st * sa
    result[..., 0, 3] = a * ct
    result[..., 1, 0] = st
    result[..., 1, 1] = ct * ca
    result[..., 1, 2] = -ct * sa
    result[..., 1, 3] = a * st
    result[..., 2, 1] = sa
    result[..., 2, 2] = ca
    result[..., 2, 3] = d
    result[..., 3, 3] = 1.0
    return result


def dh_frames(rows: np.ndarray, q: np.ndarray, tool: np.ndarray | None = None) -> np.ndarray:
    """Base-frame poses of DH frames 0..n and the tool: (n,) -> (n+2, 4, 4); (N, n) -> (N, n+2, 4, 4).

    Frame 0 is the identity; frame i (i >= 1) is the pose after joint i; the last entry is frame n
    times `tool`. Frame i-1's z axis is joint i's axis and its origin lies on that axis.
    """
    rows = np.asarray(rows, dtype=float)
    q = np.asarray(q, dtype=float)
    single = q.ndim == 1
    q_batch = q[None, :] if single else q
    count = q_batch.shape[0]
    n = rows.shape[0]
    frames = np.empty((count, n + 2, 4, 4))
    frames[:, 0] = np.eye(4)
    for index in range(n):
        offset, d, a, alpha, sign = rows[index]
        link = dh_transform(sign * q_batch[:, index] + offset, d, a, alpha)
        frames[:, index + 1] = frames[:, index] @ link
    frames[:, n + 1] = frames[:, n] @ (np.eye(4) if tool is None else np.asarray(tool, dtype=float))
    return frames[0] if single else frames


def fk_dh(rows: np.ndarray, q: np.ndarray, tool: np.ndarray | None = None) -> np.ndarray:
    """Base-frame tool pose from a DH table: (n,) -> (4, 4); (N, n) -> (N, 4, 4).

    Example (the UR3's official DH table at q = 0: arm stretched along -x):

    >>> ur3 = [[0, 0.1519, 0, np.pi / 2, 1], [0, 0, -0.24365, 0, 1], [0, 0, -0.21325, 0, 1],
    ...        [0, 0.11235, 0, np.pi / 2, 1], [0, 0.08535, 0, -np.pi / 2, 1], [0, 0.0819, 0, 0, 1]]
    >>> np.round(fk_dh(ur3, np.zeros(6))[:3, 3], 5).tolist()
    [-0.4569, -0.19425, 0.06655]
    """
    frames = dh_frames(rows, q, tool)
    return frames[..., -1, :, :]


def dh_chain_frames_fast(
    rows: tuple[tuple[float, ...], ...], q, start: tuple[float, ...] | None = None
) -> list[tuple[float, ...]]:
    """DH frames 0..n as flat 12-tuples (r00 r01 r02 px r10 r11 r12 py r20 r21 r22 pz), plain floats.

    `rows` are (theta_offset, d, a, cos_alpha, sin_alpha, sign) tuples (alpha pre-computed, see
    `fast_rows`); frame 0 is `start` (e.g. T_world_base) or the identity; the tool is not applied.
    Used by the numerical IK, where small numpy arrays would cost more than the arithmetic.
    """
    frame = start or (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0)
    frames = [frame]
    for (offset, d, a, ca, sa, sign), angle in zip(rows, q):
        theta = sign * angle + offset
        ct, st = math.cos(theta), math.sin(theta)
        r00, r01, r02, px, r10, r11, r12, py, r20, r21, r22, pz = frame
        # columns of the link rotation: x' = (ct, st, 0), y' = (-st ca, ct ca, sa), z' = (st sa, -ct sa, ca)
        x0, x1, x2 = r00 * ct + r01 * st, r10 * ct + r11 * st, r20 * ct + r21 * st
        y0, y1, y2 = r01 * ct - r00 * st, r11 * ct - r10 * st, r21 * ct - r20 * st
        frame = (
            x0, y0 * ca + r02 * sa, r02 * ca - y0 * sa, px + a * x0 + d * r02,
            x1, y1 * ca + r12 * sa, r12 * ca - y1 * sa, py + a * x1 + d * r12,
            x2, y2 * ca + r22 * sa, r22 * ca - y2 * sa, pz + a * x2 + d * r22,
        )  # fmt: skip
        frames.append(frame)
    return frames


def fast_rows(rows: np.ndarray) -> tuple[tuple[float, ...], ...]:
    """DH rows (theta_offset, d, a, alpha, sign) -> (theta_offset, d, a, cos alpha, sin alpha, sign) tuples."""
    return tuple(
        (float(o), float(d), float(a), math.cos(alpha), math.sin(alpha), float(sign))
        for o, d, a, alpha, sign in np.asarray(rows, dtype=float)
    )


def compose_flat(first: tuple[float, ...], second: tuple[float, ...]) -> tuple[float, ...]:
    """Product of two rigid transforms given as flat 12-tuples (see dh_chain_frames_fast)."""
    a00, a01, a02, ax, a10, a11, a12, ay, a20, a21, a22, az = first
    b00, b01, b02, bx, b10, b11, b12, by, b20, b21, b22, bz = second
    return (
        a00 * b00 + a01 * b10 + a02 * b20,
        a00 * b01 + a01 * b11 + a02 * b21,
        a00 * b02 + a01 * b12 + a02 * b22,
        a00 * bx + a01 * by + a02 * bz + ax,
        a10 * b00 + a11 * b10 + a12 * b20,
        a10 * b01 + a11 * b11 + a12 * b21,
        a10 * b02 + a11 * b12 + a12 * b22,
        a10 * bx + a11 * by + a12 * bz + ay,
        a20 * b00 + a21 * b10 + a22 * b20,
        a20 * b01 + a21 * b11 + a22 * b21,
        a20 * b02 + a21 * b12 + a22 * b22,
        a20 * bx + a21 * by + a22 * bz + az,
    )


def flat_from_matrix(matrix: np.ndarray) -> tuple[float, ...]:
    """The flat 12-tuple of a 4x4 transform's top three rows."""
    return tuple(float(x) for x in np.asarray(matrix, dtype=float)[:3].reshape(-1))


def matrix_from_flat(flat: tuple[float, ...]) -> np.ndarray:
    """The 4x4 matrix of a flat 12-tuple."""
    return np.array([flat[0:4], flat[4:8], flat[8:12], (0.0, 0.0, 0.0, 1.0)])
