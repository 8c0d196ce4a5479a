"""Batch numerical IK: the Levenberg-Marquardt of ik_numeric run on N full-pose targets at once.

Every iteration is a handful of numpy array expressions over all unfinished targets (DH frames,
geometric Jacobians, rotation errors, N damped 6x6 solves), so 10,000 poses cost about as much as a
few hundred scalar solves. Targets not solved from the seed get rounds of random restarts, like the
scalar solver. DH-described arms only (the fast path); others use the scalar solver per target.
"""

from __future__ import annotations

import numpy as np

from armlab.kinematics.ik_numeric import DAMPING_GAIN, DAMPING_MIN, MAX_STEP_RAD
from armlab.kinematics.screws import matrix_log3, so3_to_vec

RESTART_REPLICAS = 4  # random starts tried side by side per unsolved target in each restart round


def dh_pose_and_jacobian(rows, tool, T_world_base, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World tool poses (N, 4, 4) and geometric Jacobians (N, 6, n) (rows vx vy vz wx wy wz) of a DH chain.

    The frames are composed column by column (x, y, z axes and origin as (N, 3) arrays), which is
    several times cheaper than stacks of 4x4 products for the many small chains of an IK batch.
    """
    rows = np.asarray(rows, dtype=float)
    base = np.asarray(T_world_base, dtype=float)
    count, dof = q.shape
    x = np.broadcast_to(base[:3, 0], (count, 3))
    y = np.broadcast_to(base[:3, 1], (count, 3))
    z = np.broadcast_to(base[:3, 2], (count, 3))
    p = np.broadcast_to(base[:3, 3], (count, 3))
    axes, origins = np.empty((count, dof, 3)), np.empty((count, dof, 3))
    for index in range(dof):
        offset, d, a, alpha, sign = rows[index]
        axes[:, index], origins[:, index] = z * sign, p
        theta = sign * q[:, index] + offset
        ct, st = np.cos(theta)[:, None], np.sin(theta)[:, None]
        ca, sa = np.cos(alpha), np.sin(alpha)
        x_new = ct * x + st * y
        y_rot = ct * y - st * x
        p = p + a * x_new + d * z
        x, y, z = x_new, ca * y_rot + sa * z, ca * z - sa * y_rot
    tool = np.asarray(tool, dtype=float)
    pose = np.empty((count, 4, 4))
    rotation = np.stack([x, y, z], axis=2)
    pose[:, :3, :3] = rotation @ tool[:3, :3]
    pose[:, :3, 3] = p + rotation @ tool[:3, 3]
    pose[:, 3] = (0.0, 0.0, 0.0, 1.0)
    linear = np.cross(axes, pose[:, None, :3, 3] - origins)
    jacobian = np.concatenate([linear, axes], axis=2).transpose(0, 2, 1)
    return pose, jacobian


def rotation_error_batch(R_target: np.ndarray, R_current: np.ndarray) -> np.ndarray:
    """Rotation vectors (N, 3) of R_target R_current^T (world frame), as ik_numeric.rotation_error."""
    error = R_target @ R_current.transpose(0, 2, 1)
    skew = np.stack([error[:, 2, 1] - error[:, 1, 2], error[:, 0, 2] - error[:, 2, 0], error[:, 1, 0] - error[:, 0, 1]], 1)
    cos_angle = np.clip((np.trace(error, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
    sin_norm = np.linalg.norm(skew, axis=1)  # 2 sin(angle)
    angle = np.arccos(cos_angle)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(cos_angle > 0.999999, 0.5, angle / sin_norm)
    result = skew * scale[:, None]
    for index in np.flatnonzero((sin_norm < 1e-6) & (cos_angle < 0.0)):  # near pi: the careful log
        result[index] = so3_to_vec(matrix_log3(error[index]))
    return result


def _fit_limits(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Wrap by 2*pi toward the range (up to two turns), then clip to the limits."""
    two_pi = 2.0 * np.pi
    for _ in range(2):
        q = np.where((q > upper) & (q - two_pi >= lower), q - two_pi, q)
        q = np.where((q < lower) & (q + two_pi <= upper), q + two_pi, q)
    return np.clip(q, lower, upper)


def solve_pose_batch(
    rows,
    tool,
    T_world_base,
    T_world_targets: np.ndarray,
    q_seed: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    position_tol_m: float = 1e-4,
    rotation_tol_rad: float = np.radians(0.1),
    max_iterations: int = 30,
    max_attempts: int = 10,
    random_seed: int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Joint vectors (N, n) reaching world poses (N, 4, 4); returns (q, ok, position_error_m, rotation_error_rad).

    Rows with ok False hold the best attempt (never within both tolerances). Reproducible: restarts
    draw from a generator seeded with `random_seed`.
    """
    count, dof = q_seed.shape
    rng = np.random.default_rng(random_seed)
    best_q = q_seed.copy()
    best_position = np.full(count, np.inf)
    best_rotation = np.full(count, np.inf)
    target_p, target_R = T_world_targets[:, :3, 3], T_world_targets[:, :3, :3]
    tight_pos, tight_rot = position_tol_m * 1e-2, rotation_tol_rad * 1e-2
    todo = np.arange(count)
    for attempt in range(max_attempts):
        if todo.size == 0:
            break
        # the seed first; then RESTART_REPLICAS random starts per unsolved target side by side
        owners = todo if attempt == 0 else np.repeat(todo, RESTART_REPLICAS)  # target of each row of q
        q = q_seed[todo] if attempt == 0 else rng.uniform(lower, upper, size=(owners.size, dof))
        q = _fit_limits(q, lower, upper)
        running = np.arange(owners.size)  # rows of q still iterating
        previous = np.full(owners.size, np.inf)
        stalled = np.zeros(owners.size, dtype=int)
        for _ in range(max_iterations):
            if running.size == 0:
                break
            rows_global = owners[running]
            pose, jacobian = dh_pose_and_jacobian(rows, tool, T_world_base, q[running])
            error = np.concatenate(
                [target_p[rows_global] - pose[:, :3, 3], rotation_error_batch(target_R[rows_global], pose[:, :3, :3])], 1
            )
            position_error = np.linalg.norm(error[:, :3], axis=1)
            rotation_error = np.linalg.norm(error[:, 3:], axis=1)
            better = position_error + rotation_error < best_position[rows_global] + best_rotation[rows_global]
            improved = rows_global[better]  # (a target's replicas may repeat here: the last one wins, consistently)
            best_q[improved] = q[running[better]]
            best_position[improved] = position_error[better]
            best_rotation[improved] = rotation_error[better]
            energy = 0.5 * (position_error**2 + rotation_error**2)
            stalled[running] = np.where(energy > 0.98 * previous[running], stalled[running] + 1, 0)
            previous[running] = np.minimum(previous[running], energy)
            keep = ~((position_error < tight_pos) & (rotation_error < tight_rot)) & (stalled[running] < 6)
            if attempt > 0:  # a replica whose target another replica already solved can stop
                keep &= ~((best_position[rows_global] <= position_tol_m) & (best_rotation[rows_global] <= rotation_tol_rad))
            running, jacobian, error, energy = running[keep], jacobian[keep], error[keep], energy[keep]
            if running.size == 0:
                break
            jac_t = jacobian.transpose(0, 2, 1)
            normal = jac_t @ jacobian
            normal[:, np.arange(dof), np.arange(dof)] += (DAMPING_GAIN * energy + DAMPING_MIN)[:, None]
            step = np.linalg.solve(normal, (jac_t @ error[:, :, None]))[:, :, 0]
            norm = np.linalg.norm(step, axis=1)
            step *= np.minimum(1.0, MAX_STEP_RAD / np.maximum(norm, 1e-300))[:, None]
            q[running] = _fit_limits(q[running] + step, lower, upper)
        solved = (best_position[todo] <= position_tol_m) & (best_rotation[todo] <= rotation_tol_rad)
        todo = todo[~solved]
    ok = (best_position <= position_tol_m) & (best_rotation <= rotation_tol_rad)
    # among the 2*pi equivalents within the limits, the one nearest the seed (joints spanning > 2*pi)
    for shift in (-2.0 * np.pi, 2.0 * np.pi):
        shifted = best_q + shift
        nearer = (shifted >= lower) & (shifted <= upper) & (np.abs(shifted - q_seed) < np.abs(best_q - q_seed))
        best_q = np.where(nearer, shifted, best_q)
    return best_q, ok, best_position, best_rotation
