"""The arm model the station plans with: the nominal ArmModel, corrected by the arm's calibration when it has one
(armlab.kinematics.arm_calibration). One object, held by the station (Station.model); installing a calibration
swaps one reference inside it, so every planner that holds the station's model (click-grab, jobs, Cartesian jog,
pose moves, Cartesian replay, the safety gate, the self filter) moves with the calibrated arm from then on.

fk(q) is where the gripper stands for commanded joints q (the calibrated model); ik solves the nominal model,
then corrects its target a few times (fixed point) until the calibrated fk meets the requested position,
pitch and, when one is asked for, the fingers' yaw (the closing axis across the block's faces, mod 90 degrees:
without it the base's yaw and the wrist's zero offset turned the fingers ~5 degrees off the block) within
IK_TOLERANCE_M / IK_TOLERANCE_RAD. Without a calibration everything is the nominal model's.
Anything else (limits, names, home, config) is the nominal model's.
"""

from __future__ import annotations

import math

import numpy as np

from armlab.kinematics.arm_calibration import ArmCalibration, calibrated_fk, gravity_torques, link_angles
from armlab.kinematics.errors import Unreachable
from armlab.kinematics.rx200_geometry import approach_pitch_rad

IK_ITERATIONS = 8
IK_TOLERANCE_M = 1e-5
IK_TOLERANCE_RAD = 1e-4


class CalibratedArm:
    """The nominal model with (or without) an ArmCalibration; the ArmModel interface."""

    def __init__(self, nominal, calibration: ArmCalibration | None = None) -> None:
        self.nominal = nominal.nominal if isinstance(nominal, CalibratedArm) else nominal
        self._calibration = calibration

    def __getattr__(self, name: str):  # limits, names, poses, config, within_limits, ...: the nominal model's
        return getattr(self.nominal, name)

    @property
    def calibration(self) -> ArmCalibration | None:
        return self._calibration

    def set_calibration(self, calibration: ArmCalibration | None) -> None:
        """Use this calibration from now on (None: the nominal model). One reference: atomic for readers."""
        self._calibration = calibration

    @property
    def T_world_base(self) -> np.ndarray:
        cal = self._calibration
        base = np.asarray(self.nominal.T_world_base, float)
        if cal is None:
            return self.nominal.T_world_base
        out = cal.correction(base[:3, 3]) @ base
        out.flags.writeable = False
        return out

    # ------------------------------------------------------------------ forward

    def fk(self, q) -> np.ndarray:
        cal = self._calibration
        if cal is None:
            return self.nominal.fk(q)
        return calibrated_fk(self.nominal, cal, self.nominal._joint_vectors(q))

    def fk_measured(self, q_read) -> np.ndarray:
        """Where the gripper stands for joint readings (the servo's part of the droop is in them already)."""
        cal = self._calibration
        if cal is None:
            return self.nominal.fk(q_read)
        return calibrated_fk(self.nominal, cal, self.nominal._joint_vectors(q_read), measured=True)

    def command_holding(self, q_read) -> np.ndarray:
        """The joint command that holds the arm at rest where it reads q_read: the reading less the servo's steady
        error under the arm's weight (P-only servos hold a load tau at servo_compliance * tau past their goal, up to
        0.05 rad at the RX200's far reach); q_read itself without a calibration (no steady error known)."""
        cal = self._calibration
        q = np.asarray(q_read, float)
        if cal is None:
            return q.copy()
        servo = np.asarray(cal.servo_compliance_rad_per_nm, float)
        command = q - servo * gravity_torques(self.nominal, q)
        return q - servo * gravity_torques(self.nominal, command)  # the torque at the command, as the fit measured it

    def joint_frames(self, q) -> np.ndarray:
        cal = self._calibration
        if cal is None:
            return self.nominal.joint_frames(q)
        q_link = link_angles(self.nominal, cal, self.nominal._joint_vectors(q))
        C = cal.correction(np.asarray(self.nominal.T_world_base, float)[:3, 3])
        return C @ np.asarray(self.nominal.joint_frames(q_link))

    def pitch_of(self, q) -> float:
        return approach_pitch_rad(self.fk(q), tuple(np.asarray(self.T_world_base)[:3, 3]))

    def gravity_torques(self, q) -> np.ndarray:
        return gravity_torques(self.nominal, q)

    # ------------------------------------------------------------------ inverse

    def ik(self, position_m, pitch=None, yaw=None, q_seed=None) -> np.ndarray:
        return self.ik_with_pitch(position_m, pitch, yaw, q_seed)[0]

    def ik_with_pitch(self, position_m, pitch=None, yaw=None, q_seed=None) -> tuple[np.ndarray, float]:
        q, used = self.nominal.ik_with_pitch(position_m, pitch, yaw, q_seed)
        if self._calibration is None:
            return q, used
        goal = np.asarray(position_m, float)
        aim, aim_pitch, aim_yaw = goal.copy(), float(used), yaw
        for _ in range(IK_ITERATIONS):
            T = self.fk(q)
            miss = T[:3, 3] - goal
            pitch_miss = self.pitch_of(q) - used
            yaw_miss = 0.0 if yaw is None else finger_yaw_miss_rad(T, yaw)
            if np.linalg.norm(miss) < IK_TOLERANCE_M and abs(pitch_miss) < IK_TOLERANCE_RAD and abs(yaw_miss) < IK_TOLERANCE_RAD:
                return q, used
            aim, aim_pitch = aim - miss, aim_pitch - pitch_miss
            aim_yaw = None if yaw is None else aim_yaw - yaw_miss
            q, _ = self.nominal.ik_with_pitch(aim, aim_pitch, aim_yaw, q_seed)
        if np.linalg.norm(self.fk(q)[:3, 3] - goal) > 100 * IK_TOLERANCE_M:
            raise Unreachable(f"target {goal.round(4).tolist()} m: the calibrated arm does not converge there", "out of reach")
        return q, used

    def ik_batch(self, positions_m, pitch=None, yaw=None, q_seed=None) -> tuple[np.ndarray, np.ndarray]:
        q, ok = self.nominal.ik_batch(positions_m, pitch, yaw, q_seed)
        if self._calibration is None or not ok.any():
            return q, ok
        goal = np.asarray(positions_m, float)
        base = tuple(np.asarray(self.T_world_base)[:3, 3])
        nominal_base = tuple(np.asarray(self.nominal.T_world_base)[:3, 3])
        rows = np.flatnonzero(ok)
        wanted = np.array([approach_pitch_rad(T, nominal_base) for T in self.nominal.fk(q[rows])])
        aim, aim_pitch = goal.copy(), np.full(len(goal), np.nan)
        aim_pitch[rows] = wanted
        yaw_goal = None if yaw is None else np.broadcast_to(np.asarray(yaw, float), (len(goal),)).copy()
        yaw_all = None if yaw is None else yaw_goal.copy()
        seeds = None if q_seed is None else np.broadcast_to(np.asarray(q_seed, float), q.shape)
        for _ in range(IK_ITERATIONS):
            T = self.fk(q[rows])
            miss = T[:, :3, 3] - goal[rows]
            pitch_miss = np.array([approach_pitch_rad(t, base) for t in T]) - wanted
            yaw_miss = np.zeros(len(rows)) if yaw is None else np.array([finger_yaw_miss_rad(t, y) for t, y in zip(T, yaw_goal[rows])])
            if np.abs(miss).max() < IK_TOLERANCE_M and np.abs(pitch_miss).max() < IK_TOLERANCE_RAD and np.abs(yaw_miss).max() < IK_TOLERANCE_RAD:
                break
            aim[rows] -= miss
            aim_pitch[rows] -= pitch_miss
            if yaw_all is not None:
                yaw_all[rows] -= yaw_miss
            solved, fine = self.nominal.ik_batch(aim[rows], aim_pitch[rows], None if yaw_all is None else yaw_all[rows],
                                                 None if seeds is None else seeds[rows])
            q[rows[fine]] = solved[fine]
            lost = rows[~fine]
            q[lost], ok[lost] = np.nan, False
            keep = fine
            rows, wanted = rows[keep], wanted[keep]
        return q, ok

    def ik_pose(self, T_world_target, q_seed=None) -> np.ndarray:
        """A full pose on the calibrated arm: the nominal pose IK at the target moved back by the base correction
        (or the nominal position IK when that pose is not the nominal arm's), then Gauss-Newton on the calibrated
        fk; within 0.1 mm and 0.1 deg like the nominal's, else Unreachable."""
        target = np.asarray(T_world_target, float)
        cal = self._calibration
        if cal is None:
            return self.nominal.ik_pose(target, q_seed)
        aim = np.linalg.inv(cal.correction(np.asarray(self.nominal.T_world_base, float)[:3, 3])) @ target
        try:
            q = self.nominal.ik_pose(aim, q_seed)
        except Unreachable:
            q = self.nominal.ik(aim[:3, 3], pitch=None, yaw=None, q_seed=q_seed)
        for _ in range(2 * IK_ITERATIONS):
            error = _pose_error(self.fk(q), target)
            if np.linalg.norm(error[:3]) < IK_TOLERANCE_M and np.linalg.norm(error[3:]) < IK_TOLERANCE_RAD:
                break
            J = np.empty((6, len(q)))
            for j in range(len(q)):
                shifted = q.copy()
                shifted[j] += 1e-7
                J[:, j] = (_pose_error(self.fk(shifted), target) - error) / 1e-7
            q = q - np.linalg.lstsq(J, error, rcond=None)[0]
        error = _pose_error(self.fk(q), target)
        if np.linalg.norm(error[:3]) > 1e-4 or np.linalg.norm(error[3:]) > np.radians(0.1) or not self.nominal.within_limits(q):
            raise Unreachable(f"pose at {target[:3, 3].round(4).tolist()} m: out of reach of the calibrated arm (error "
                              f"{np.linalg.norm(error[:3]) * 1000:.2f} mm / {np.degrees(np.linalg.norm(error[3:])):.2f} deg)",
                              "out of reach")
        return q

    def ik_pose_batch(self, T_world_targets, q_seed=None) -> tuple[np.ndarray, np.ndarray]:
        if self._calibration is None:
            return self.nominal.ik_pose_batch(T_world_targets, q_seed)
        targets = np.asarray(T_world_targets, float)
        q, ok = np.full((len(targets), self.nominal.dof), np.nan), np.zeros(len(targets), bool)
        for i, target in enumerate(targets):
            try:
                q[i], ok[i] = self.ik_pose(target, q_seed), True
            except Unreachable:
                pass
        return q, ok


def finger_yaw_miss_rad(T_world_tool: np.ndarray, yaw_rad: float) -> float:
    """How far (rad, wrapped to +-45 degrees) the fingers' closing axis (the tool's y), seen from above, is turned from
    the nearest face normal of a block at yaw_rad (yaw + k*90 degrees): 0 when the fingers close across its faces."""
    axis = np.asarray(T_world_tool, float)[:3, 1]
    if math.hypot(axis[0], axis[1]) < 1e-6:  # the fingers close vertically: no yaw to meet
        return 0.0
    quarter = math.pi / 2
    return (math.atan2(axis[1], axis[0]) - float(yaw_rad) + quarter / 2) % quarter - quarter / 2


def _pose_error(T: np.ndarray, target: np.ndarray) -> np.ndarray:
    """(6,): position difference (m) and the rotation's axis-angle vector (rad) from target to T."""
    R = target[:3, :3].T @ T[:3, :3]
    angle = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) * 0.5
    return np.concatenate([T[:3, 3] - target[:3, 3], target[:3, :3] @ angle])
