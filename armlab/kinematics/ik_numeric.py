"""Numerical inverse kinematics for any arm in config: Levenberg-Marquardt with joint limits and
random restarts (after Sugihara 2011: damping = error energy + a small constant).

The solver sees the arm through a `kinematics(q) -> (tool pose, Jacobian columns)` callable, all in
the world frame. `DhKinematics` is the fast one (plain floats from a DH table); `PoxKinematics` works
from a product-of-exponentials description with numpy. Success means the pose error is within
`position_tol_m` and `rotation_tol_rad`; otherwise the caller gets ok = False, never a silent guess.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

import numpy as np

from armlab.kinematics.dh import compose_flat, dh_chain_frames_fast, fast_rows, flat_from_matrix
from armlab.kinematics.screws import fk_space, jacobian_space, matrix_log3, so3_to_vec

Flat = tuple[float, ...]  # a rigid transform as 12 floats, row-major 3x4

# Damping lambda = gain * error energy + minimum (Sugihara's rule, scaled: 0.1 converged fastest on
# UR3 and RX200 random poses, median ~10 iterations); joint steps are capped at 1 rad (norm).
DAMPING_GAIN = 0.1
DAMPING_MIN = 1e-6
MAX_STEP_RAD = 1.0


def _solve_spd(matrix: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """Solve a small positive-definite system. np.linalg.solve's Python wrapper costs as much as the
    solve itself at 6x6, so its gufunc is called directly when this numpy has it (same result)."""
    if _SOLVE_GUFUNC is not None:
        return _SOLVE_GUFUNC(matrix, vector)
    return np.linalg.solve(matrix, vector)


try:  # numpy's compiled solver behind np.linalg.solve (private; fall back to the public call)
    from numpy.linalg import _umath_linalg

    _SOLVE_GUFUNC = _umath_linalg.solve1
except (ImportError, AttributeError):  # pragma: no cover - other numpy builds
    _SOLVE_GUFUNC = None


@dataclass(frozen=True)
class DhKinematics:
    """World-frame tool pose and geometric Jacobian of a DH chain, in plain floats."""

    rows: tuple[tuple[float, ...], ...]  # (theta_offset, d, a, cos alpha, sin alpha, sign)
    tool: Flat
    world_base: Flat

    @classmethod
    def from_arrays(cls, rows: np.ndarray, tool: np.ndarray, T_world_base: np.ndarray) -> DhKinematics:
        return cls(rows=fast_rows(rows), tool=flat_from_matrix(tool), world_base=flat_from_matrix(T_world_base))

    def pose(self, q) -> Flat:
        """T_world_tool as a flat tuple (FK only)."""
        return compose_flat(dh_chain_frames_fast(self.rows, q, self.world_base)[-1], self.tool)

    def __call__(self, q) -> tuple[Flat, list[tuple[float, ...]]]:
        """(T_world_tool as a flat tuple, Jacobian columns (vx, vy, vz, wx, wy, wz) per joint)."""
        world = dh_chain_frames_fast(self.rows, q, self.world_base)
        tool = compose_flat(world[-1], self.tool)
        px, py, pz = tool[3], tool[7], tool[11]
        columns = []
        for index, (_offset, _d, _a, _ca, _sa, sign) in enumerate(self.rows):
            frame = world[index]
            zx, zy, zz = frame[2] * sign, frame[6] * sign, frame[10] * sign
            dx, dy, dz = px - frame[3], py - frame[7], pz - frame[11]
            columns.append((zy * dz - zz * dy, zz * dx - zx * dz, zx * dy - zy * dx, zx, zy, zz))
        return tool, columns


@dataclass(frozen=True)
class PoxKinematics:
    """World-frame tool pose and Jacobian from a PoX description (numpy; slower, fully general)."""

    home: np.ndarray
    screw_axes: np.ndarray
    T_world_base: np.ndarray

    def __call__(self, q) -> tuple[Flat, list[tuple[float, ...]]]:
        q = np.asarray(q, dtype=float)
        T_world_tool = self.T_world_base @ fk_space(self.home, self.screw_axes, q)
        jac = jacobian_space(self.screw_axes, q)
        rotation = self.T_world_base[:3, :3]
        omega = rotation @ jac[:3]
        # space twist -> velocity of the tool point: v + w x p (in the base frame), then rotate to world
        p_base = (np.linalg.inv(self.T_world_base) @ T_world_tool)[:3, 3]
        linear = rotation @ (jac[3:] + np.cross(jac[:3].T, p_base).T)
        columns = [tuple(linear[:, i]) + tuple(omega[:, i]) for i in range(jac.shape[1])]
        return flat_from_matrix(T_world_tool), columns


def rotation_error(target: Flat, current: Flat) -> tuple[float, float, float]:
    """Rotation vector (axis * angle, world frame) of R_target R_current^T, plain floats."""
    t00, t01, t02, _, t10, t11, t12, _, t20, t21, t22, _ = target
    c00, c01, c02, _, c10, c11, c12, _, c20, c21, c22, _ = current
    # E = T C^T
    e00 = t00 * c00 + t01 * c01 + t02 * c02
    e11 = t10 * c10 + t11 * c11 + t12 * c12
    e22 = t20 * c20 + t21 * c21 + t22 * c22
    e01 = t00 * c10 + t01 * c11 + t02 * c12
    e10 = t10 * c00 + t11 * c01 + t12 * c02
    e02 = t00 * c20 + t01 * c21 + t02 * c22
    e20 = t20 * c00 + t21 * c01 + t22 * c02
    e12 = t10 * c20 + t11 * c21 + t12 * c22
    e21 = t20 * c10 + t21 * c11 + t22 * c12
    vx, vy, vz = e21 - e12, e02 - e20, e10 - e01
    cos_angle = max(-1.0, min(1.0, (e00 + e11 + e22 - 1.0) / 2.0))
    sin_norm = math.sqrt(vx * vx + vy * vy + vz * vz)  # = 2 sin(angle)
    if cos_angle > 0.999999:
        return 0.5 * vx, 0.5 * vy, 0.5 * vz
    angle = math.acos(cos_angle)
    if sin_norm < 1e-6:  # angle near pi: the general formula loses the axis; use the careful log
        error_matrix = np.array([[e00, e01, e02], [e10, e11, e12], [e20, e21, e22]])
        return tuple(float(v) for v in so3_to_vec(matrix_log3(error_matrix)))
    scale = angle / sin_norm
    return vx * scale, vy * scale, vz * scale


@dataclass(frozen=True)
class NumericResult:
    """Outcome of `solve_pose`: q (tuple), ok, final position/rotation error, attempts used."""

    q: tuple[float, ...]
    ok: bool
    position_error_m: float
    rotation_error_rad: float
    attempts: int


def _fit_limits(q: list[float], lower: tuple[float, ...], upper: tuple[float, ...]) -> None:
    """In place: wrap each angle by 2*pi toward the range, then clip to the limits."""
    two_pi = 2.0 * math.pi
    for i, value in enumerate(q):
        while value > upper[i] and value - two_pi >= lower[i]:
            value -= two_pi
        while value < lower[i] and value + two_pi <= upper[i]:
            value += two_pi
        q[i] = min(upper[i], max(lower[i], value))


def _closest_equivalent(q: list[float], seed: tuple[float, ...], lower, upper) -> None:
    """In place: for joints whose range spans more than 2*pi, pick the equivalent angle nearest the seed."""
    two_pi = 2.0 * math.pi
    for i, value in enumerate(q):
        for candidate in (value - two_pi, value + two_pi):
            if lower[i] <= candidate <= upper[i] and abs(candidate - seed[i]) < abs(q[i] - seed[i]):
                q[i] = candidate


def solve_pose(
    kinematics,
    T_world_target: Flat,
    q_seed: tuple[float, ...],
    lower: tuple[float, ...],
    upper: tuple[float, ...],
    position_tol_m: float = 1e-4,
    rotation_tol_rad: float = math.radians(0.1),
    max_iterations: int = 60,
    max_attempts: int = 30,
    random_seed: int = 0,
    position_only: bool = False,
) -> NumericResult:
    """Joint vector whose tool pose matches `T_world_target` (flat tuple), by LM with restarts.

    The first attempt starts at q_seed; later ones at uniform random joints (a seeded generator, so
    results are reproducible). Iterates until the error is 100x inside the tolerances (to leave
    margin), and accepts a solution within the tolerances. `position_only` ignores orientation.
    """
    dof = len(q_seed)
    rng = random.Random(random_seed)
    best_q, best_position, best_rotation, best_attempt = tuple(q_seed), math.inf, math.inf, 0
    tight_pos, tight_rot = position_tol_m * 1e-2, rotation_tol_rad * 1e-2
    diagonal = slice(None, None, dof + 1)
    for attempt in range(1, max_attempts + 1):
        q = list(q_seed) if attempt == 1 else [rng.uniform(lo, hi) for lo, hi in zip(lower, upper)]
        _fit_limits(q, lower, upper)
        previous_energy, stalled = math.inf, 0
        for _ in range(max_iterations):
            pose, columns = kinematics(q)
            ex, ey, ez = T_world_target[3] - pose[3], T_world_target[7] - pose[7], T_world_target[11] - pose[11]
            position_error = math.sqrt(ex * ex + ey * ey + ez * ez)
            if position_only:
                rotation_error_rad, error = 0.0, (ex, ey, ez)
            else:
                rx, ry, rz = rotation_error(T_world_target, pose)
                rotation_error_rad = math.sqrt(rx * rx + ry * ry + rz * rz)
                error = (ex, ey, ez, rx, ry, rz)
            if position_error + rotation_error_rad < best_position + best_rotation:
                best_q, best_position, best_rotation, best_attempt = tuple(q), position_error, rotation_error_rad, attempt
            if position_error < tight_pos and rotation_error_rad < tight_rot:
                break
            energy = 0.5 * (position_error * position_error + rotation_error_rad * rotation_error_rad)
            stalled = stalled + 1 if energy > 0.98 * previous_energy else 0
            if stalled >= 6:
                break
            previous_energy = min(previous_energy, energy)
            # damped normal equations (J^T J + lambda I) dq = J^T e, with J^T built row by row
            jac_t = np.array(columns)
            if position_only:
                jac_t = jac_t[:, :3]
            normal = jac_t @ jac_t.T
            normal.flat[diagonal] += DAMPING_GAIN * energy + DAMPING_MIN
            step = _solve_spd(normal, jac_t @ np.array(error)).tolist()
            norm = math.sqrt(sum(d * d for d in step))
            scale = MAX_STEP_RAD / norm if norm > MAX_STEP_RAD else 1.0
            q = [value + scale * delta for value, delta in zip(q, step)]
            _fit_limits(q, lower, upper)
        if best_position <= position_tol_m and best_rotation <= rotation_tol_rad:
            solution = list(best_q)
            _closest_equivalent(solution, q_seed, lower, upper)
            return NumericResult(tuple(solution), True, best_position, best_rotation, attempt)
    return NumericResult(best_q, False, best_position, best_rotation, best_attempt)
