"""ArmModel: one arm from config/arms/ with FK (single or batched), joint frames and IK, and load_arm.

All poses are in the world (board) frame, in metres, with the gripper frame's x axis the approach
axis and its y axis the fingers' closing axis. `fk`/`ik` pick the fastest exact method for the arm
(closed form for the RX200 family, DH/PoX and numerical IK otherwise); `fk_pox`/`fk_dh` expose the
two descriptions so tests can check they agree.

>>> arm = load_arm("rx200")
>>> np.round(arm.fk(np.zeros(5))[:3, 3], 6).tolist()   # world = (-base_y, base_x, z)
[0.0, 0.408575, 0.30457]
>>> q = arm.ik([0.0, 0.25, 0.05])                        # straight down over a block
>>> bool(np.allclose(arm.fk(q)[:3, 3], [0.0, 0.25, 0.05], atol=1e-9))
True
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from armlab.config import load_config, resolve_config_path
from armlab.errors import ConfigError, InvalidInput
from armlab.kinematics import ik_numeric, ik_numeric_batch, ik_rx200, ik_rx200_batch
from armlab.kinematics.arm_config import ArmConfig
from armlab.kinematics.dh import dh_frames, fk_dh, matrix_from_flat
from armlab.kinematics.errors import Unreachable
from armlab.kinematics.rx200_geometry import HALF_PI, Rx200Geometry, approach_pitch_rad, fk_rx200_batch, fk_rx200_flat
from armlab.kinematics.screws import fk_space, matrix_exp6_batch, point_on_screw_axis, vec_to_so3


def _readonly(array) -> np.ndarray:
    result = np.array(array, dtype=float)
    result.flags.writeable = False
    return result


def _finite_array(value, shape_text: str, name: str) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"{name}: expected numbers {shape_text}, got {value!r}") from error
    if not np.all(np.isfinite(array)):
        raise InvalidInput(f"{name}: values must be finite (no NaN or infinity), got {array.tolist()}")
    return array


def _exp_terms(screw_axes: np.ndarray) -> tuple[np.ndarray, ...]:
    """The terms of matrix_exp6_batch that do not depend on the angle, per screw axis (w | v), stacked: [w], [w]^2,
    v, [w] v, [w]^2 v."""
    W = np.array([vec_to_so3(axis[:3]) for axis in screw_axes])
    W2 = W @ W
    V = np.asarray(screw_axes, dtype=float)[:, 3:]
    return W, W2, V, np.einsum("nij,nj->ni", W, V), np.einsum("nij,nj->ni", W2, V)


def _position_tuple(position_m) -> tuple[float, float, float]:
    """A finite [x, y, z] as three floats; a fast path for lists and tuples of floats (scalar IK speed)."""
    if isinstance(position_m, list | tuple) and len(position_m) == 3:
        if all(isinstance(v, float | int) and not isinstance(v, bool) and math.isfinite(v) for v in position_m):
            return float(position_m[0]), float(position_m[1]), float(position_m[2])
    position = _finite_array(position_m, "[x, y, z]", "position_m")
    if position.shape != (3,):
        raise InvalidInput(f"position_m: expected [x, y, z], got shape {position.shape}")
    return float(position[0]), float(position[1]), float(position[2])


class ArmModel:
    """A validated arm: limits and poses as numpy arrays, FK, joint frames and IK (world frame)."""

    def __init__(self, config: ArmConfig, source: str = "arm config") -> None:
        self.config = config
        self.name = config.name
        self.dof = len(config.joint_names)
        self.joint_names = tuple(config.joint_names)
        self.lower_rad = _readonly(np.radians(config.limits.lower_deg))
        self.upper_rad = _readonly(np.radians(config.limits.upper_deg))
        self.velocity_limit_rad_s = _readonly(config.limits.velocity_rad_s)
        self.accel_limit_rad_s2 = _readonly(config.limits.acceleration_rad_s2)
        self.home_rad = _readonly(config.poses.home_rad)
        self.sleep_rad = _readonly(config.poses.sleep_rad)
        self.T_world_base = _readonly(config.T_world_base)
        self.link_radii_m = _readonly(config.link_radii_m if config.link_radii_m is not None else np.zeros(self.dof))
        self._home_tuple = tuple(float(v) for v in self.home_rad)
        self._lower = tuple(float(v) for v in self.lower_rad)
        self._upper = tuple(float(v) for v in self.upper_rad)
        self._pox = None if config.pox is None else (np.asarray(config.pox.M, float), np.asarray(config.pox.screw_axes, float))
        self._dh = None if config.dh is None else (np.asarray(config.dh.rows, float), np.asarray(config.dh.tool, float))
        self._geometry = Rx200Geometry.from_config(config, source) if config.family == "rx200" else None
        if self._dh is not None:
            self._numeric = ik_numeric.DhKinematics.from_arrays(self._dh[0], self._dh[1], self.T_world_base)
        else:
            self._numeric = ik_numeric.PoxKinematics(self._pox[0], self._pox[1], np.asarray(self.T_world_base))
        self._joint_homes = self._build_joint_homes(source)
        self._exp_terms = None if self._joint_homes is None else _exp_terms(self._pox[1])
        self._check_descriptions_agree(source)

    # ------------------------------------------------------------------ construction checks

    def _build_joint_homes(self, source: str) -> np.ndarray | None:
        """Home (q = 0) base-frame pose of each joint origin and the gripper point, from urdf_origins."""
        if self.config.urdf_origins is None:
            return None
        homes = np.broadcast_to(np.eye(4), (self.dof + 1, 4, 4)).copy()
        homes[:, :3, 3] = np.cumsum(np.asarray(list(self.config.urdf_origins.values()), dtype=float), axis=0)
        home_M, axes = self._pox
        for index, name in enumerate(self.joint_names):
            axis_point = point_on_screw_axis(axes[index])
            offset = homes[index, :3, 3] - axis_point
            if np.linalg.norm(offset - np.dot(offset, axes[index, :3]) * axes[index, :3]) > 1e-6:
                raise ConfigError(f"{source}: urdf_origins.{name} does not lie on pox.screw_axes[{self.joint_names.index(name)}]")
        if np.linalg.norm(homes[-1, :3, 3] - home_M[:3, 3]) > 1e-6:
            raise ConfigError(
                f"{source}: urdf_origins.gripper_point puts the gripper point at {homes[-1, :3, 3].round(6).tolist()}, "
                f"but pox.M says {home_M[:3, 3].round(6).tolist()}"
            )
        homes[-1, :3, :3] = home_M[:3, :3]
        return homes

    def _check_descriptions_agree(self, source: str) -> None:
        """ConfigError if the DH and PoX descriptions (when both given) disagree by more than 1 micron."""
        if self._pox is None or self._dh is None:
            return
        rng = np.random.default_rng(0)
        q = rng.uniform(self.lower_rad, self.upper_rad, size=(16, self.dof))
        q[0] = 0.0
        gap = np.abs(fk_space(*self._pox, q) - fk_dh(self._dh[0], q, self._dh[1])).max()
        if gap > 1e-6:
            raise ConfigError(f"{source}: dh and pox disagree (largest pose difference {gap:.3g}); check dh.rows and dh.tool")

    # ------------------------------------------------------------------ limits

    def _joint_vectors(self, q, name: str = "q") -> np.ndarray:
        array = _finite_array(q, f"of shape ({self.dof},) or (N, {self.dof})", name)
        if array.ndim not in (1, 2) or array.shape[-1] != self.dof:
            raise InvalidInput(f"{name}: expected shape ({self.dof},) or (N, {self.dof}) for {self.name}, got {array.shape}")
        return array

    def within_limits(self, q) -> bool:
        """True if every joint of q (dof,) or (N, dof) is within its limits (1e-9 rad tolerance)."""
        array = self._joint_vectors(q)
        return bool(np.all(array >= self.lower_rad - 1e-9) and np.all(array <= self.upper_rad + 1e-9))

    def clip_to_limits(self, q) -> np.ndarray:
        """q clipped into the joint limits (same shape)."""
        return np.clip(self._joint_vectors(q), self.lower_rad, self.upper_rad)

    # ------------------------------------------------------------------ forward kinematics

    def fk(self, q) -> np.ndarray:
        """World pose of the gripper point: (dof,) -> (4, 4); (N, dof) -> (N, 4, 4)."""
        # fast path for one joint vector: plain floats, no small numpy arrays
        values = q.tolist() if isinstance(q, np.ndarray) and q.ndim == 1 else q
        if isinstance(values, list | tuple) and len(values) == self.dof:
            if all(isinstance(v, float | int) and math.isfinite(v) for v in values):
                if self._geometry is not None:
                    return matrix_from_flat(fk_rx200_flat(self._geometry, values))
                if self._dh is not None:
                    return matrix_from_flat(self._numeric.pose(values))
        array = self._joint_vectors(q)
        if self._geometry is not None:
            if array.ndim == 1:
                return matrix_from_flat(fk_rx200_flat(self._geometry, array.tolist()))
            return fk_rx200_batch(self._geometry, array)
        if array.ndim == 1 and self._dh is not None:
            return matrix_from_flat(self._numeric.pose(array.tolist()))
        return self.fk_dh(array) if self._dh is not None else self.fk_pox(array)

    def fk_pox(self, q) -> np.ndarray:
        """World pose from the product-of-exponentials description (ValueError if the arm has none)."""
        if self._pox is None:
            raise ValueError(f"{self.name} has no pox description")
        return np.asarray(self.T_world_base) @ fk_space(*self._pox, self._joint_vectors(q))

    def fk_dh(self, q) -> np.ndarray:
        """World pose from the DH table (ValueError if the arm has none)."""
        if self._dh is None:
            raise ValueError(f"{self.name} has no dh description")
        return np.asarray(self.T_world_base) @ fk_dh(self._dh[0], self._joint_vectors(q), self._dh[1])

    def joint_frames(self, q) -> np.ndarray:
        """World poses of each joint's origin and finally the gripper point: (dof,) -> (dof+1, 4, 4).

        For arms with urdf_origins (the RX200) these are the URDF joint origins (waist at 0.06566 m,
        shoulder, elbow, wrist_angle, wrist_rotate, gripper point; translations only, as in the RX200
        URDF), each oriented as its parent link; otherwise the DH frames, whose origins lie on each
        joint's axis. The safety checker keeps every one of them at z >= 0.
        Accepts (N, dof) too, giving (N, dof+1, 4, 4).
        """
        array = self._joint_vectors(q)
        single = array.ndim == 1
        if single and self._exp_terms is not None:
            return self._joint_frames_one(array)
        batch = array[None, :] if single else array
        if self._joint_homes is not None:
            axes = self._pox[1]
            frames = np.empty((batch.shape[0], self.dof + 1, 4, 4))
            product = np.broadcast_to(np.eye(4), (batch.shape[0], 4, 4))  # exp([S1]q1)...exp([Si]qi)
            for index in range(self.dof + 1):
                frames[:, index] = product @ self._joint_homes[index]
                if index < self.dof:
                    product = product @ matrix_exp6_batch(axes[index], batch[:, index])
        else:
            frames = dh_frames(self._dh[0], batch, self._dh[1])
            frames = np.concatenate([frames[:, : self.dof], frames[:, -1:]], axis=1)
        frames = np.asarray(self.T_world_base) @ frames
        return frames[0] if single else frames

    def _joint_frames_one(self, q: np.ndarray) -> np.ndarray:
        """joint_frames of one configuration (urdf_origins arms): the batch path's products, with every joint's
        exp([S_i] q_i) from matrix_exp6_batch's formula at once (its q-independent terms kept: _exp_terms) instead
        of one call per joint; ~4x faster (the recorder's /tf at 30 Hz, the safety checks of single poses)."""
        W, W2, V, WV, W2V = self._exp_terms
        sin_q, one_minus_cos = np.sin(q), 1.0 - np.cos(q)
        exps = np.zeros((self.dof, 4, 4))
        exps[:, :3, :3] = np.eye(3) + sin_q[:, None, None] * W + one_minus_cos[:, None, None] * W2
        exps[:, :3, 3] = q[:, None] * V + one_minus_cos[:, None] * WV + (q - sin_q)[:, None] * W2V
        exps[:, 3, 3] = 1.0
        frames = np.empty((self.dof + 1, 4, 4))
        product = np.eye(4)  # exp([S1]q1)...exp([Si]qi)
        for index in range(self.dof):
            frames[index] = product @ self._joint_homes[index]
            product = product @ exps[index]
        frames[self.dof] = product @ self._joint_homes[self.dof]
        return np.asarray(self.T_world_base) @ frames

    # ------------------------------------------------------------------ inverse kinematics

    def _seed(self, q_seed) -> tuple[float, ...]:
        if q_seed is None:
            return self._home_tuple
        array = _finite_array(q_seed, f"of shape ({self.dof},)", "q_seed")
        if array.shape != (self.dof,):
            raise InvalidInput(f"q_seed: expected shape ({self.dof},) for {self.name}, got {array.shape}")
        return tuple(float(v) for v in array)

    @staticmethod
    def _scalar(value, name: str) -> float | None:
        if value is None:
            return None
        if isinstance(value, float | int) and not isinstance(value, bool) and math.isfinite(value):
            return float(value)
        array = _finite_array(value, "(one number)", name)
        if array.shape != ():
            raise InvalidInput(f"{name}: expected one number, got shape {array.shape}")
        return float(array)

    def ik(self, position_m, pitch=None, yaw=None, q_seed=None) -> np.ndarray:
        """Joint vector putting the gripper point at `position_m` (world, metres); raises Unreachable.

        pitch: approach axis below the horizontal (rad; pi/2 = straight down), in the vertical plane
        through the base axis and the target; None = straight down if reachable, else the steepest
        reachable pitch (searched). yaw: the block's yaw in the world (rad); sets wrist_rotate so the
        fingers (which close along the gripper frame's y axis) close across the block's faces, choosing
        among the pi/2-apart equivalents the one within limits nearest the seed's wrist_rotate. For the
        RX200 pointing straight down the fingers close along the world direction at angle
        (waist - wrist_rotate): along world x at waist = wrist_rotate = 0. yaw None keeps the seed's
        wrist_rotate. q_seed (default: home) picks among the solutions: the valid one nearest it.
        Raises Unreachable ("out of reach", "joint limit (<joint>)", "below the table"); ValueError
        for malformed input.
        """
        return self.ik_with_pitch(position_m, pitch, yaw, q_seed)[0]

    def ik_with_pitch(self, position_m, pitch=None, yaw=None, q_seed=None) -> tuple[np.ndarray, float]:
        """Like `ik`, also returning the pitch used (the one found when pitch is None)."""
        target = _position_tuple(position_m)
        pitch_value, yaw_value = self._scalar(pitch, "pitch"), self._scalar(yaw, "yaw")
        seed = self._seed(q_seed)
        if self._geometry is not None:
            q, used = ik_rx200.solve(self._geometry, target, pitch_value, yaw_value, seed)
            return np.array(q), used
        return self._ik_generic(target, pitch_value, yaw_value, seed)

    def ik_batch(self, positions_m, pitch=None, yaw=None, q_seed=None) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised ik: positions (N, 3); pitch/yaw None, a number or (N,); q_seed (dof,) or (N, dof).

        Returns (q (N, dof), ok (N,) bool); rows with ok False are NaN.
        """
        positions = _finite_array(positions_m, "of shape (N, 3)", "positions_m")
        if positions.ndim != 2 or positions.shape[1] != 3:
            raise InvalidInput(f"positions_m: expected shape (N, 3), got {positions.shape}")
        count = positions.shape[0]

        def per_target(value, name):
            if value is None:
                return None
            array = _finite_array(value, f"(a number or shape ({count},))", name)
            if array.shape not in ((), (count,)):
                raise InvalidInput(f"{name}: expected a number or shape ({count},), got {array.shape}")
            return np.broadcast_to(array, (count,)).astype(float)

        pitches, yaws = per_target(pitch, "pitch"), per_target(yaw, "yaw")
        seeds = np.broadcast_to(self.home_rad, (count, self.dof)) if q_seed is None else self._joint_vectors(q_seed, "q_seed")
        seeds = np.broadcast_to(seeds, (count, self.dof)).astype(float)
        if self._geometry is not None:
            q, ok, _pitch = ik_rx200_batch.solve_batch(self._geometry, positions, pitches, yaws, seeds)
            return q, ok
        q = np.full((count, self.dof), np.nan)
        ok = np.zeros(count, dtype=bool)
        for i in range(count):
            try:
                q[i] = self.ik(
                    positions[i], None if pitches is None else pitches[i], None if yaws is None else yaws[i], seeds[i]
                )
                ok[i] = True
            except Unreachable:
                pass
        return q, ok

    def ik_pose(self, T_world_target, q_seed=None) -> np.ndarray:
        """Joint vector reaching a full world pose (numerical LM, any arm), within 0.1 mm and 0.1 deg.

        Raises Unreachable ("below the table" or "out of reach" with the residual error).
        """
        target = _finite_array(T_world_target, "of shape (4, 4)", "T_world_target")
        if target.shape != (4, 4):
            raise InvalidInput(f"T_world_target: expected shape (4, 4), got {target.shape}")
        rotation = target[:3, :3]
        if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or not np.allclose(target[3], [0, 0, 0, 1]):
            raise InvalidInput("T_world_target: not a rigid transform (rotation not orthonormal or last row not [0, 0, 0, 1])")
        if target[2, 3] < 0.0:
            raise Unreachable(f"pose at {target[:3, 3].round(4).tolist()} m: below the table (z < 0)", "below the table")
        seed = self._seed(q_seed)
        flat = tuple(float(v) for v in target[:3].reshape(-1))
        result = ik_numeric.solve_pose(self._numeric, flat, seed, self._lower, self._upper)
        if not result.ok:
            raise Unreachable(
                f"pose at {target[:3, 3].round(4).tolist()} m: out of reach (best error "
                f"{result.position_error_m * 1000:.2f} mm / {math.degrees(result.rotation_error_rad):.2f} deg "
                f"after {result.attempts} starts)",
                "out of reach",
            )
        return np.array(result.q)

    def ik_pose_batch(self, T_world_targets, q_seed=None) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised ik_pose: poses (N, 4, 4) -> (q (N, dof), ok (N,)); failed rows are NaN.

        Same tolerances (0.1 mm, 0.1 deg) and restarts as ik_pose; targets below the board fail.
        """
        targets = _finite_array(T_world_targets, "of shape (N, 4, 4)", "T_world_targets")
        if targets.ndim != 3 or targets.shape[1:] != (4, 4):
            raise InvalidInput(f"T_world_targets: expected shape (N, 4, 4), got {targets.shape}")
        rotation = targets[:, :3, :3]
        gram = rotation.transpose(0, 2, 1) @ rotation
        if not np.allclose(gram, np.eye(3), atol=1e-6) or not np.allclose(targets[:, 3], [0, 0, 0, 1]):
            raise InvalidInput("T_world_targets: not all rigid transforms (rotation not orthonormal or last row not [0, 0, 0, 1])")
        count = targets.shape[0]
        seeds = np.broadcast_to(self.home_rad if q_seed is None else self._joint_vectors(q_seed, "q_seed"), (count, self.dof))
        seeds = np.array(seeds, dtype=float)
        if self._dh is None:  # no fast batch path: the scalar solver per target
            q, ok = np.full((count, self.dof), np.nan), np.zeros(count, dtype=bool)
            for i in range(count):
                try:
                    q[i], ok[i] = self.ik_pose(targets[i], seeds[i]), True
                except Unreachable:
                    pass
            return q, ok
        q, ok, _position, _rotation = ik_numeric_batch.solve_pose_batch(
            self._dh[0], self._dh[1], np.asarray(self.T_world_base), targets, seeds,
            np.asarray(self.lower_rad), np.asarray(self.upper_rad),
        )  # fmt: skip
        ok &= targets[:, 2, 3] >= 0.0
        q[~ok] = np.nan
        return q, ok

    def _ik_generic(self, target, pitch, yaw, seed) -> tuple[np.ndarray, float]:
        """Position + pitch (+ yaw) IK for arms without a closed form: numerical, on built target poses."""
        x, y, z = target
        if z < 0.0:
            raise Unreachable(f"target ({x:.4f}, {y:.4f}, {z:.4f}) m: below the table (z < 0)", "below the table")
        reach = ik_numeric.solve_pose(self._numeric, (1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z), seed, self._lower, self._upper, position_only=True)
        if not reach.ok:
            raise Unreachable(
                f"target ({x:.4f}, {y:.4f}, {z:.4f}) m: out of reach (closest {reach.position_error_m * 1000:.1f} mm away)",
                "out of reach",
            )
        if pitch is not None:
            steps = [pitch]
        else:  # straight down first, then ever shallower (5 degree steps, alternating sides)
            tilted = [HALF_PI + side * k * math.radians(5.0) for k in range(1, 37) for side in (-1.0, 1.0)]
            steps = [HALF_PI, *[p for p in tilted if -HALF_PI - 1e-9 <= p <= math.pi + 1e-9]]
        base = np.asarray(self.T_world_base)[:3, 3]
        for candidate_pitch in steps:
            best, best_cost = None, math.inf
            yaws = [None] if yaw is None else [yaw + k * HALF_PI for k in range(4)]
            for candidate_yaw in yaws:
                flat = _target_pose_flat(target, base, candidate_pitch, candidate_yaw)
                result = ik_numeric.solve_pose(
                    self._numeric, flat, seed, self._lower, self._upper, max_attempts=30 if pitch is not None else 6
                )
                cost = sum(abs(a - b) for a, b in zip(result.q, seed))
                if result.ok and cost < best_cost:
                    best, best_cost = result.q, cost
            if best is not None:
                return np.array(best), float(candidate_pitch)
        pitch_text = "at any pitch" if pitch is None else f"at pitch {math.degrees(pitch):.1f} deg"
        raise Unreachable(
            f"target ({x:.4f}, {y:.4f}, {z:.4f}) m: out of reach {pitch_text} (the position alone is reachable)",
            "out of reach",
        )

    def pitch_of(self, q) -> float:
        """Approach pitch below the horizontal (rad) of joint vector q, as `ik` defines it."""
        return approach_pitch_rad(self.fk(q), tuple(np.asarray(self.T_world_base)[:3, 3]))


def _target_pose_flat(target, base_xyz, pitch: float, yaw: float | None) -> tuple[float, ...]:
    """Flat world pose with approach axis at `pitch` below the horizontal, pointing away from the base
    axis, and the closing axis (y) whose horizontal projection lies along `yaw` (or horizontal)."""
    rx, ry = target[0] - base_xyz[0], target[1] - base_xyz[1]
    norm = math.hypot(rx, ry)
    ux, uy = (rx / norm, ry / norm) if norm > 1e-9 else (1.0, 0.0)
    a = np.array([math.cos(pitch) * ux, math.cos(pitch) * uy, -math.sin(pitch)])
    d = np.array([-uy, ux, 0.0]) if yaw is None else np.array([math.cos(yaw), math.sin(yaw), 0.0])
    y_axis = a[2] * d - float(d @ a) * np.array([0.0, 0.0, 1.0])
    if np.linalg.norm(y_axis) < 1e-9:
        y_axis = np.cross([0.0, 0.0, 1.0], a)
    y_axis /= np.linalg.norm(y_axis)
    if float(y_axis @ d) < 0.0:
        y_axis = -y_axis
    z_axis = np.cross(a, y_axis)
    rotation = np.stack([a, y_axis, z_axis], axis=1)
    return tuple(float(v) for v in np.concatenate([rotation, np.asarray(target)[:, None]], axis=1).reshape(-1))


def load_arm(name_or_path: str | Path) -> ArmModel:
    """Load and validate config/arms/<name>.yaml (or a path); ConfigError naming the file and field."""
    path = resolve_config_path(name_or_path, "arms")
    return ArmModel(load_config(path, ArmConfig), str(path))
