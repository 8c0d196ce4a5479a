"""The arm's own calibration (issue 19 item 2): from poses where the camera saw the gripper's tag, fit what
makes the real arm stand elsewhere than its nominal model says, so the station can command it where it means.

The model, from commanded joints q (what the station sends) to where the gripper is (world):

    link angles  = q + joint_offset + compliance * tau(q)
    T_world_tool = C @ FK_nominal(link angles)

- joint_offset: each joint's zero as mounted (the first joint's is left out when its axis is vertical: it
  turns the arm exactly as the base's yaw does, so the yaw carries both);
- compliance (rad per N*m) of each gravity-loaded joint (a horizontal axis at home), times tau, the gravity
  torque about it from the nominal model (armlab ArmConfig.link_masses_kg, each link's mass halfway between
  its joint origin and the next): the servo's steady error (P-only, no gravity feed-forward) plus the gears'
  and links' give. A servo holds a load tau at an error tau / kp and a gear gives tau / k, so the droop is
  linear in the torque below the stall: one number per joint;
- C: the base's correction in the world, about the nominal base origin: a shift (x, y, z), a yaw, and with
  fit_tilt also roll and pitch (the board's tilt under the arm).

The readings show the servo's part of the droop (the encoder sits on the motor): servo_compliance, the slope
of (commanded - reading) against tau, lets FK of a reading (fk_measured) add only the rest.

Levenberg-Marquardt with forward-difference Jacobians over the marker's position (the tag's centre in the
gripper-point frame, as the workcell says), numpy only. ArmCalibrationError (InvalidInput) refuses too few
usable poses, NaN, or a fit no better than the nominal model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from armlab.errors import InvalidInput
from armlab.kinematics.rotations import rotation_about

GRAVITY_M_S2 = 9.81
MIN_POSES = 12
MAX_ITERATIONS = 60
OUTLIER_FACTOR, OUTLIER_MIN_M = 3.0, 0.003  # a pose further off the fit than both: fitted again without it
MIN_OFFSET_LEVER_M = 0.03  # a joint's offset is fitted only when its axis passes at least this far from the marker
MIN_IMPROVEMENT_M = 1e-4  # a fit must bring the mean residual down by this much to be worth using
_STEP = {"offset": 1e-6, "compliance": 1e-5, "shift": 1e-6, "angle": 1e-6}


class ArmCalibrationError(InvalidInput):
    """The arm cannot be calibrated from these poses (too few, NaN, or the fit is no better); says why."""


# ---------------------------------------------------------------------------------------------- the load


def _pox_axes(model) -> np.ndarray:
    if model.config.pox is None or model.config.urdf_origins is None:
        raise ArmCalibrationError(f"{model.name}: arm calibration needs the pox axes and urdf_origins (the RX200 family)")
    return np.asarray(model.config.pox.screw_axes, float)[:, :3]


def gravity_loaded(model) -> np.ndarray:
    """(dof,) bool: joints whose axis is horizontal at home and gravity loads (more than 0.01 N*m somewhere within
    the limits: not the RX200's wrist_rotate, whose link's centre lies on its axis)."""
    axes = np.asarray(model.T_world_base, float)[:3, :3] @ _pox_axes(model).T
    q = np.random.default_rng(0).uniform(model.lower_rad, model.upper_rad, (16, model.dof))
    return (np.abs(axes[2]) < 0.5) & (np.abs(gravity_torques(model, q)).max(axis=0) > 0.01)


def offset_joints(model, marker_in_tool_m=None) -> np.ndarray:
    """(dof,) bool: joints whose zero offset is fitted: all but a first joint with a vertical axis (the base yaw),
    and (given the marker's position in the gripper-point frame) any joint whose axis passes within
    MIN_OFFSET_LEVER_M of the marker: turning it hardly moves the marker, so its fitted offset is noise (the RX200's
    wrist_rotate, 18 mm from the tag: 0.3 mm a degree; fitted, it came out -4.6 deg for a drawn +1.7 and turned the
    fingers 5.5 deg off the blocks). Such a joint keeps its nominal zero."""
    axes = np.asarray(model.T_world_base, float)[:3, :3] @ _pox_axes(model).T
    chosen = np.ones(model.dof, bool)
    chosen[0] = abs(axes[2, 0]) < 0.9
    if marker_in_tool_m is not None:
        frames = np.asarray(model.joint_frames(np.zeros(model.dof)))  # joint origins, then the gripper point (home)
        marker_world = frames[-1][:3, :3] @ np.asarray(marker_in_tool_m, float) + frames[-1][:3, 3]
        for j in range(model.dof):
            lever = np.cross(marker_world - frames[j][:3, 3], axes[:, j] / np.linalg.norm(axes[:, j]))
            chosen[j] &= bool(np.linalg.norm(lever) >= MIN_OFFSET_LEVER_M)
    return chosen


def gravity_torques(model, q_rad) -> np.ndarray:
    """Gravity torque (N*m) about each joint's positive axis, (dof,) or (N, dof) like q, from the nominal model's
    link masses (equal masses when the arm file gives none) at their links' midpoints."""
    q = np.asarray(q_rad, float)
    single = q.ndim == 1
    batch = np.atleast_2d(q)
    frames = np.asarray(model.joint_frames(batch))  # (N, dof+1, 4, 4): joint origins, then the gripper point
    masses = np.asarray(model.config.link_masses_kg if model.config.link_masses_kg is not None else np.full(model.dof, 0.2), float)
    origins = frames[:, :, :3, 3]
    centres = 0.5 * (origins[:, :-1] + origins[:, 1:])  # (N, dof, 3): link k from joint k's origin to the next
    axes = np.einsum("nkij,kj->nki", frames[:, :-1, :3, :3], _pox_axes(model))  # joint k's axis in the world
    weight = np.array([0.0, 0.0, -GRAVITY_M_S2])
    torques = np.zeros(batch.shape)
    for j in range(model.dof):
        lever = centres[:, j:] - origins[:, j : j + 1]  # (N, dof-j, 3)
        moment = np.cross(lever, masses[j:, None] * weight)  # (N, dof-j, 3)
        torques[:, j] = np.einsum("nki,ni->n", moment, axes[:, j])
    return torques[0] if single else torques


def chain_fk(model, q_rad, length_delta_m=None) -> np.ndarray:
    """World pose(s) of the gripper point from the URDF origins (each one's length changed by length_delta_m,
    (dof+1,), along its own direction) and the pox axes: model.fk's pose when the deltas are zero."""
    q = np.asarray(q_rad, float)
    batch = np.atleast_2d(q)
    origins = np.asarray(list(model.config.urdf_origins.values()), float)  # (dof+1, 3): parent-relative
    if length_delta_m is not None:
        lengths = np.linalg.norm(origins, axis=1)
        scale = np.where(lengths > 0, (lengths + np.asarray(length_delta_m, float)) / np.where(lengths > 0, lengths, 1.0), 1.0)
        origins = origins * scale[:, None]
    axes = _pox_axes(model)
    rotation = np.broadcast_to(np.eye(3), (len(batch), 3, 3))
    position = np.zeros((len(batch), 3))
    for k in range(model.dof):
        position = position + rotation @ origins[k]
        rotation = rotation @ rotation_about(axes[k], batch[:, k])
    position = position + rotation @ origins[-1]
    T = np.broadcast_to(np.eye(4), (len(batch), 4, 4)).copy()
    T[:, :3, :3] = rotation @ np.asarray(model.config.pox.M, float)[:3, :3]
    T[:, :3, 3] = position
    T = np.asarray(model.T_world_base, float) @ T
    return T[0] if q.ndim == 1 else T


def length_joints(model) -> np.ndarray:
    """Indices of the URDF origins whose length the fit moves: those between two gravity-loaded joints and the one
    after the last of them (upper arm, forearm, wrist on the RX200). The base's (height: the base's z) and the
    gripper point's (the tag does not see it) are left out."""
    loaded = np.flatnonzero(gravity_loaded(model))
    if len(loaded) == 0:
        return np.zeros(0, int)
    return np.arange(loaded[0] + 1, min(loaded[-1] + 2, model.dof))


# ---------------------------------------------------------------------------------------------- the result


def _correction(base_origin_m: np.ndarray, values: np.ndarray) -> np.ndarray:
    """C (4x4): rotate about the base origin by yaw (z), pitch (y), roll (x) = values[3:6], then shift by values[:3]."""
    yaw, pitch, roll = values[3], values[4], values[5]
    cz, sz, cy, sy, cx, sx = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch), math.cos(roll), math.sin(roll)
    rotation = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]) @ np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]) \
        @ np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    T = np.eye(4)
    T[:3, :3] = rotation
    T[:3, 3] = base_origin_m + values[:3] - rotation @ base_origin_m
    return T


@dataclass(frozen=True)
class ArmCalibration:
    """A fitted arm: joint zero offsets (rad), compliance (rad per N*m: commanded -> link) and its servo part
    (what the readings show), the base correction [dx, dy, dz (m), yaw, pitch, roll (rad)], and the fit's
    residuals (m, per pose) with the nominal model and after."""

    joint_offset_rad: np.ndarray
    compliance_rad_per_nm: np.ndarray
    servo_compliance_rad_per_nm: np.ndarray
    base_correction: np.ndarray
    length_delta_m: np.ndarray = field(default_factory=lambda: np.zeros(0))  # per URDF origin (dof+1), or empty
    residuals_before_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    residuals_after_m: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outliers: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # indices of poses left out of the fit

    @property
    def residual_before_mm(self) -> float:
        return float(1000.0 * np.mean(self.residuals_before_m)) if len(self.residuals_before_m) else float("nan")

    @property
    def residual_mm(self) -> float:
        return float(1000.0 * np.mean(self.residuals_after_m)) if len(self.residuals_after_m) else float("nan")

    def correction(self, base_origin_m) -> np.ndarray:
        return _correction(np.asarray(base_origin_m, float), np.asarray(self.base_correction, float))

    def to_dict(self) -> dict:
        return {"joint_offset_rad": np.asarray(self.joint_offset_rad).tolist(),
                "compliance_rad_per_nm": np.asarray(self.compliance_rad_per_nm).tolist(),
                "servo_compliance_rad_per_nm": np.asarray(self.servo_compliance_rad_per_nm).tolist(),
                "base_correction": np.asarray(self.base_correction).tolist(),
                "length_delta_m": np.asarray(self.length_delta_m).tolist(),
                "residuals_before_m": np.asarray(self.residuals_before_m).tolist(),
                "residuals_after_m": np.asarray(self.residuals_after_m).tolist()}

    @classmethod
    def from_dict(cls, data: dict, dof: int) -> ArmCalibration:
        """Back from to_dict; ArmCalibrationError when a field is missing, of the wrong size or not finite."""
        try:
            values = {name: np.asarray(data[name], float) for name in
                      ("joint_offset_rad", "compliance_rad_per_nm", "servo_compliance_rad_per_nm", "base_correction")}
            residuals = {name: np.asarray(data.get(name, []), float) for name in ("residuals_before_m", "residuals_after_m", "length_delta_m")}
        except (KeyError, TypeError, ValueError) as error:
            raise ArmCalibrationError(f"a stored arm calibration is unreadable: {error!r}") from None
        sizes = {"joint_offset_rad": dof, "compliance_rad_per_nm": dof, "servo_compliance_rad_per_nm": dof, "base_correction": 6}
        for name, size in sizes.items():
            if values[name].shape != (size,) or not np.all(np.isfinite(values[name])):
                raise ArmCalibrationError(f"a stored arm calibration's {name} is not {size} finite numbers")
        if residuals["length_delta_m"].shape not in ((0,), (dof + 1,)) or not np.all(np.isfinite(residuals["length_delta_m"])):
            raise ArmCalibrationError(f"a stored arm calibration's length_delta_m is not {dof + 1} finite numbers")
        return cls(**values, **residuals)


def link_angles(model, calibration: ArmCalibration, q_rad, measured: bool = False) -> np.ndarray:
    """Where the links stand for commanded joints q (or for joint readings, measured=True: the servo's part of
    the droop is in them already)."""
    q = np.asarray(q_rad, float)
    compliance = np.asarray(calibration.compliance_rad_per_nm, float)
    if measured:
        compliance = compliance - np.asarray(calibration.servo_compliance_rad_per_nm, float)
    return q + np.asarray(calibration.joint_offset_rad, float) + compliance * gravity_torques(model, q)


def calibrated_fk(model, calibration: ArmCalibration, q_rad, measured: bool = False) -> np.ndarray:
    """World pose(s) of the gripper point (like model.fk) on the calibrated arm."""
    C = calibration.correction(np.asarray(model.T_world_base, float)[:3, 3])
    q_link = link_angles(model, calibration, q_rad, measured)
    if len(calibration.length_delta_m):
        return C @ chain_fk(model, q_link, calibration.length_delta_m)
    return C @ np.asarray(model.fk(q_link))


# ---------------------------------------------------------------------------------------------- the fit


@dataclass(frozen=True)
class _Layout:
    """Which parameters the fit moves, in its vector's order: offsets, compliances (one per loaded joint, or one
    common factor on the servo's measured compliance: `servo`), base correction, link lengths."""

    offsets: np.ndarray  # joint indices
    compliances: np.ndarray  # joint indices (per-joint compliance), or empty with servo given
    servo: np.ndarray | None  # the readings' compliance per joint: the fit moves one factor (1 + rho) on it
    base: np.ndarray  # indices into [dx, dy, dz, yaw, pitch, roll]
    lengths: np.ndarray  # URDF origin indices

    @property
    def _compliance_count(self) -> int:
        return 1 if self.servo is not None else len(self.compliances)

    @property
    def size(self) -> int:
        return len(self.offsets) + self._compliance_count + len(self.base) + len(self.lengths)

    def start(self) -> np.ndarray:
        return np.zeros(self.size)

    def steps(self) -> np.ndarray:
        base_steps = [_STEP["shift"] if i < 3 else _STEP["angle"] for i in self.base]
        compliance_step = 1e-4 if self.servo is not None else _STEP["compliance"]
        return np.array([_STEP["offset"]] * len(self.offsets) + [compliance_step] * self._compliance_count + base_steps
                        + [_STEP["shift"]] * len(self.lengths))

    def unpack(self, p: np.ndarray, dof: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        offsets, compliance, base, lengths = np.zeros(dof), np.zeros(dof), np.zeros(6), np.zeros(dof + 1)
        a, b = len(self.offsets), len(self.offsets) + self._compliance_count
        c = b + len(self.base)
        offsets[self.offsets], base[self.base], lengths[self.lengths] = p[:a], p[b:c], p[c:]
        if self.servo is not None:
            compliance = self.servo * (1.0 + p[a])
        else:
            compliance[self.compliances] = p[a:b]
        return offsets, compliance, base, lengths


def _marker_points(model, q_link: np.ndarray, marker_m: np.ndarray, C: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    T = C @ chain_fk(model, q_link, lengths)  # (N, 4, 4)
    return T[:, :3, :3] @ marker_m + T[:, :3, 3]


def _check_inputs(model, commanded, measured, seen) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    arrays = []
    for name, value, width in (("commanded joints", commanded, model.dof), ("joint readings", measured, model.dof),
                               ("marker points", seen, 3)):
        try:
            array = np.asarray(value, float)
        except (TypeError, ValueError):
            raise ArmCalibrationError(f"{name}: not numbers") from None
        if array.ndim != 2 or array.shape[1] != width:
            raise ArmCalibrationError(f"{name}: expected shape (N, {width}), got {array.shape}")
        if not np.all(np.isfinite(array)):
            raise ArmCalibrationError(f"{name}: NaN or infinite values (pose {int(np.argwhere(~np.isfinite(array))[0, 0])})")
        arrays.append(array)
    if len({len(a) for a in arrays}) != 1:
        raise ArmCalibrationError(f"{len(arrays[0])} commanded poses, {len(arrays[1])} readings, {len(arrays[2])} marker points")
    return arrays[0], arrays[1], arrays[2]


def fit_arm(model, commanded_rad, measured_rad, seen_world_m, marker_in_tool_m, min_poses: int = MIN_POSES,
            fit_tilt: bool = False, fit_lengths: bool = True, per_joint_compliance: bool | None = None) -> ArmCalibration:
    """Fit an ArmCalibration to N poses: commanded joints (N, dof), the joint readings there (N, dof), and the
    gripper's tag seen by the calibrated camera (N, 3, world m); the tag's centre in the gripper-point frame.
    ArmCalibrationError: fewer than min_poses, NaN, or a fit whose mean residual is not below the nominal's.

    The compliance: by default the servo's part is measured from the readings (servo_compliance) and the fit
    moves one factor (1 + rho) on it for the part behind the encoder, the same for every joint (a joint's gears
    are as stiff as its servo is strong: kp and gear stiffness both scale with the stall torque). The marker
    sits 70 mm beyond the wrist's axis, too close to tell the wrist's own compliance from its offset and length
    apart; the readings tell it. per_joint_compliance (None: when the readings show no droop) fits one per
    loaded joint instead."""
    q_cmd, q_read, seen = _check_inputs(model, commanded_rad, measured_rad, seen_world_m)
    if len(q_cmd) < max(min_poses, 1):
        raise ArmCalibrationError(f"the arm calibration needs at least {min_poses} poses where the gripper was seen, got {len(q_cmd)}")
    marker = np.asarray(marker_in_tool_m, float)
    loaded = gravity_loaded(model)
    tau = gravity_torques(model, q_cmd)
    servo = servo_compliance(q_cmd, q_read, tau, loaded)
    if per_joint_compliance is None:
        per_joint_compliance = not np.all(servo[loaded] > 0.0)
    layout = _Layout(np.flatnonzero(offset_joints(model, marker)), np.flatnonzero(loaded), None if per_joint_compliance else servo,
                     np.arange(6) if fit_tilt else np.arange(4), length_joints(model) if fit_lengths else np.zeros(0, int))
    base_origin = np.asarray(model.T_world_base, float)[:3, 3]

    def residuals(p: np.ndarray) -> np.ndarray:
        offsets, compliance, base, lengths = layout.unpack(p, model.dof)
        points = _marker_points(model, q_cmd + offsets + compliance * tau, marker, _correction(base_origin, base), lengths)
        return (points - seen).ravel()

    before = np.linalg.norm(_marker_points(model, q_cmd, marker, np.eye(4), np.zeros(model.dof + 1)) - seen, axis=1)
    keep = np.ones(len(q_cmd), bool)
    p = _solve(lambda p: residuals(p)[np.repeat(keep, 3)], layout.start(), layout.steps())
    after = np.linalg.norm(residuals(p).reshape(-1, 3), axis=1)
    outliers = after > max(OUTLIER_FACTOR * float(np.median(after)), OUTLIER_MIN_M)
    if outliers.any() and int((~outliers).sum()) >= max(min_poses, int(np.ceil(0.75 * len(q_cmd)))):
        keep = ~outliers  # a sighting far off the rest (a tag seen edge-on, a finger over it): fitted without
        p = _solve(lambda p: residuals(p)[np.repeat(keep, 3)], p, layout.steps())
    r = residuals(p)[np.repeat(keep, 3)]
    before = before[keep]
    after = np.linalg.norm(r.reshape(-1, 3), axis=1)
    if not np.all(np.isfinite(after)) or after.mean() > before.mean() - MIN_IMPROVEMENT_M:
        raise ArmCalibrationError(f"the arm calibration's residual ({1000 * after.mean():.2f} mm mean) is no better than the "
                                  f"nominal model's ({1000 * before.mean():.2f} mm): not used")
    offsets, compliance, base, lengths = layout.unpack(p, model.dof)
    return ArmCalibration(offsets, compliance, servo, base, lengths, before, after, np.flatnonzero(~keep))


def _solve(residuals, p: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Levenberg-Marquardt from p with forward-difference Jacobians (steps per parameter)."""
    r = residuals(p)
    cost, damping = float(r @ r), 1e-3
    for _ in range(MAX_ITERATIONS):
        J = np.empty((len(r), len(p)))
        for i in range(len(p)):
            shifted = p.copy()
            shifted[i] += steps[i]
            J[:, i] = (residuals(shifted) - r) / steps[i]
        A, g = J.T @ J, J.T @ r
        improved = False
        while damping < 1e8:
            delta = np.linalg.solve(A + damping * np.diag(np.diag(A) + 1e-12), -g)
            r_new = residuals(p + delta)
            cost_new = float(r_new @ r_new)
            if cost_new < cost:
                p, r, improved = p + delta, r_new, True
                damping = max(damping / 3.0, 1e-9)
                break
            damping *= 4.0
        if not improved:
            break
        converged = cost - cost_new < 1e-12 * max(cost, 1e-12)
        cost = cost_new
        if converged:
            break
    return p


def servo_compliance(q_cmd: np.ndarray, q_read: np.ndarray, tau: np.ndarray, loaded: np.ndarray) -> np.ndarray:
    """Per gravity-loaded joint, the least-squares slope (through zero) of (reading - commanded) on the torque:
    the part of the droop the encoder sees (the motor holds a load tau at tau / kp past its goal; 0 elsewhere)."""
    slope = np.zeros(q_cmd.shape[1])
    for j in np.flatnonzero(loaded):
        load = float(tau[:, j] @ tau[:, j])
        if load > 1e-9:
            slope[j] = float(tau[:, j] @ (q_read[:, j] - q_cmd[:, j])) / load
    return slope
