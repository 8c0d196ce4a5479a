"""Operator jog steps of the gripper: a straight Cartesian step along a world axis, or a rotation step
(pitch, wrist roll), planned by IK at every sample and verified by FK before anything moves.

A Cartesian step (axis x, y or z) moves the gripper point along that world axis and keeps the
gripper's pitch (approach axis below the horizontal, in the arm's vertical plane) and yaw (heading of
the fingers' closing axis in the board plane, as GET /api/status reports it). A 5-joint arm turns the
gripper with the waist, so a step that changes the waist keeps the yaw by rolling the wrist while the
gripper points (nearly) down; level (Home) or tilted, the roll cannot hold it, and the step keeps the wrist
roll instead: the yaw turns with the waist, exactly as much (yaw_turn_rad says how much; issue 21: an X
step from Home was always refused). A pitch step turns the approach axis about the gripper point (wrist
roll unchanged); a roll step turns wrist_rotate only. Whatever cannot be kept within the tolerances (1 mm
off the asked motion, 0.5° of pitch, of yaw or of the yaw the waist gives) is refused with StepRefused
(an Unreachable) naming the numbers. An arm with six joints or more keeps
the tool's whole orientation instead (armlab.motion.pose_step, through ik_pose). Pure: no devices.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.kinematics.errors import Unreachable
from armlab.motion.cartesian import plan_path
from armlab.motion.errors import DiscontinuousPath, StepRefused
from armlab.motion.pose_path import holds_full_pose
from armlab.motion.pose_step import plan_pose_step
from armlab.motion.trajectory import (
    DEFAULT_RATE_HZ,
    START_TOLERANCE_RAD,
    check_joint_positions,
    minimum_time,
    plan_joint_move,
)

AXES = ("x", "y", "z", "pitch", "roll")
LINEAR_AXES = ("x", "y", "z")
POSITION_TOL_M = 0.001  # the gripper point stays this close to the asked motion
ORIENTATION_TOL_RAD = math.radians(0.5)  # pitch and yaw kept (or changed by the asked step) this closely
EXACT_TOL_RAD = math.radians(0.02)  # a plan that keeps the wrist roll must keep the yaw this closely, else it rolls
MAX_STEP_M = 0.1
MAX_STEP_RAD = math.pi / 4
# Holding the yaw while the waist turns by w rolls the wrist by about w / sin(pitch) and tilts the fingers:
# allowed while the gripper points nearly down (roll at most this many times the waist's turn, pitch 53-127°).
MAX_ROLL_PER_WAIST = 1.25


@dataclass(frozen=True)
class StepSpeeds:
    """Cruise speed and ramp acceleration of jog steps (already scaled by the operator's override)."""

    linear_m_s: float
    linear_accel_m_s2: float
    angular_rad_s: float
    angular_accel_rad_s2: float


@dataclass(frozen=True)
class GripperPose:
    """position_m (3,) world; pitch_rad in the arm's vertical plane (π/2 = straight down, > π/2 leaning
    back); yaw_rad the closing axis' heading from world +x (as GET /api/status reports it)."""

    position_m: np.ndarray
    pitch_rad: float
    yaw_rad: float


def gripper_poses(arm, q_rad) -> list[GripperPose]:
    """GripperPose of each joint vector of q_rad (N, dof) (FK of the arm model)."""
    T = np.asarray(arm.fk(np.atleast_2d(np.asarray(q_rad, float))), float).reshape(-1, 4, 4)
    base_xy = np.asarray(arm.T_world_base, float)[:2, 3]
    poses = []
    for pose in T:
        approach, closing = pose[:3, 0], pose[:3, 1]
        radial = pose[:2, 3] - base_xy
        norm = float(np.hypot(*radial))
        horizontal = float(approach[:2] @ (radial / norm)) if norm > 1e-9 else float(np.hypot(*approach[:2]))
        poses.append(
            GripperPose(
                position_m=pose[:3, 3].copy(),
                pitch_rad=math.atan2(-float(approach[2]), horizontal),
                yaw_rad=math.atan2(float(closing[1]), float(closing[0])),
            )
        )
    return poses


def gripper_pose(arm, q_rad) -> GripperPose:
    """GripperPose of one joint vector."""
    return gripper_poses(arm, q_rad)[0]


def angle_difference_rad(a: float, b: float) -> float:
    """a − b wrapped into (−π, π]."""
    return math.remainder(a - b, 2.0 * math.pi)


def _profile(distance: float, speed: float, accel: float) -> tuple[float, float]:
    """(duration, ramp) of a rest-to-rest trapezoid over `distance` (> 0) at speed/accel."""
    return minimum_time(speed / distance, accel / distance)


@dataclass(frozen=True)
class FingerBox:
    """A box around the open fingers in the gripper frame (x = approach, y = closing axis), metres: from
    back_m behind the gripper point to reach_m beyond it, ±half_width_m across, ±half_height_m."""

    back_m: float
    reach_m: float
    half_width_m: float
    half_height_m: float

    def corners_m(self) -> np.ndarray:
        """(8, 3) corners in the gripper frame."""
        return np.array([[x, y, z] for x in (-self.back_m, self.reach_m) for y in (-self.half_width_m, self.half_width_m)
                         for z in (-self.half_height_m, self.half_height_m)])


def plan_gripper_step(
    arm,
    q_start_rad,
    axis: str,
    amount: float,
    speeds: StepSpeeds,
    fingers: FingerBox | None = None,
    clearance_m: float = 0.0,
    rate_hz: float = DEFAULT_RATE_HZ,
) -> JointTrajectory:
    """A checked jog step from q_start: `amount` metres along world axis x|y|z, or radians of pitch|roll.

    fingers: the box the fingers occupy; every sample keeps its lowest corner clearance_m above the board
    (None: the gripper point itself). ValueError for malformed input; StepRefused / Unreachable (with the
    reason and numbers) when the step cannot be made keeping the gripper's pitch and yaw within
    ORIENTATION_TOL_RAD and the point within POSITION_TOL_M of the asked motion, or the fingers above the board.
    """
    if axis not in AXES:
        raise InvalidInput(f"axis must be one of {', '.join(AXES)}, got {axis!r}")
    amount = float(amount)
    limit = MAX_STEP_M if axis in LINEAR_AXES else MAX_STEP_RAD
    if not (math.isfinite(amount) and 0.0 < abs(amount) <= limit):
        unit = "m" if axis in LINEAR_AXES else "rad"
        raise InvalidInput(f"a {axis} step must be non-zero and at most {limit:.3f} {unit}, got {amount}")
    lower, upper = np.asarray(arm.lower_rad, float), np.asarray(arm.upper_rad, float)
    q_start = check_joint_positions("q_start", q_start_rad, lower - START_TOLERANCE_RAD, upper + START_TOLERANCE_RAD, arm.joint_names)
    q_start = np.clip(q_start, lower, upper)  # a measured start a hair outside a limit starts on it
    start = gripper_pose(arm, q_start)
    if axis == "roll":
        trajectory = _plan_roll(arm, q_start, amount, speeds, rate_hz)
        verify_step(arm, trajectory.positions_rad, axis, amount)
    elif holds_full_pose(arm):  # six joints or more: the whole orientation is kept (ik_pose)
        trajectory = plan_pose_step(arm, q_start, axis, amount, speeds, _step_text(axis, amount), rate_hz,
                                    POSITION_TOL_M, ORIENTATION_TOL_RAD)
    elif axis == "pitch":
        trajectory = _plan_pitch(arm, q_start, start, amount, speeds, rate_hz)
    else:
        trajectory = _plan_linear(arm, q_start, start, axis, amount, speeds, rate_hz)
    check_fingers_above_board(arm, trajectory.positions_rad, fingers, clearance_m, _step_text(axis, amount))
    return trajectory


def check_fingers_above_board(arm, positions_rad: np.ndarray, fingers: FingerBox | None, clearance_m: float, label: str) -> None:
    """StepRefused ('below the table') if at some sample the fingers' lowest corner (or the gripper point,
    without a finger box) comes closer than clearance_m to the board."""
    T = np.asarray(arm.fk(np.asarray(positions_rad, float)), float).reshape(-1, 4, 4)
    corners = np.zeros((1, 3)) if fingers is None else fingers.corners_m()
    lowest = np.einsum("nj,kj->nk", T[:, 2, :3], corners) + T[:, 2, 3][:, None]  # world z of each corner
    sample = int(np.argmin(lowest.min(axis=1)))
    low_m = float(lowest[sample].min())
    if low_m < clearance_m:
        raise StepRefused(
            f"{label}: the fingers would come down to z = {low_m * 1000:.1f} mm with the gripper point at "
            f"z = {T[sample, 2, 3] * 1000:.1f} mm, below the {clearance_m * 1000:.1f} mm kept above the board",
            "below the table",
        )

def _step_text(axis: str, amount: float) -> str:
    if axis in LINEAR_AXES:
        return f"{axis} step of {amount * 1000:+.1f} mm"
    return f"{axis} step of {math.degrees(amount):+.1f}°"


def _plan_linear(arm, q_start, start: GripperPose, axis: str, amount: float, speeds: StepSpeeds, rate_hz: float):
    direction = np.zeros(3)
    direction[LINEAR_AXES.index(axis)] = 1.0
    goal = start.position_m + amount * direction
    label = _step_text(axis, amount)
    if goal[2] < 0.0:
        raise StepRefused(f"{label}: the gripper point would go to z = {goal[2] * 1000:.1f} mm, below the board", "below the table")
    duration_s, ramp_s = _profile(abs(amount), speeds.linear_m_s, speeds.linear_accel_m_s2)

    def targets_at(s: np.ndarray) -> np.ndarray:
        return start.position_m[None, :] + s[:, None] * (amount * direction)[None, :]

    def pitch_at(s: np.ndarray) -> np.ndarray:
        return np.full(s.size, start.pitch_rad)

    # Keep the wrist roll when that keeps the yaw exactly (a step that leaves the waist alone), else let IK
    # roll the wrist to hold the closing axis' heading. When the roll cannot (the gripper level or tilted: the
    # roll would tip the fingers, or IK flips the wrist a quarter turn), keep the roll and let the yaw turn
    # with the waist, the one thing a 5-joint arm can do there (verified: exactly the waist's turn).
    def attempt(yaw, tol_rad, follows_waist=False):
        return _checked_path(arm, q_start, targets_at, pitch_at, yaw, duration_s, ramp_s, label, axis, amount, rate_hz, tol_rad,
                             follows_waist)

    try:
        return attempt(None, EXACT_TOL_RAD)
    except StepRefused as kept_roll:
        if kept_roll.reason != "orientation":
            raise
        try:
            return attempt(start.yaw_rad, ORIENTATION_TOL_RAD)
        except Unreachable as rolled:
            try:
                return attempt(None, ORIENTATION_TOL_RAD, follows_waist=True)
            except Unreachable as followed:
                raise StepRefused(f"{kept_roll}; rolling the wrist to hold it: {rolled}; keeping the wrist: {followed}",
                                  kept_roll.reason) from rolled


def _checked_path(
    arm, q_start, targets_at, pitch_at, yaw, duration_s, ramp_s, label, axis, amount, rate_hz, tol_rad=ORIENTATION_TOL_RAD,
    follows_waist: bool = False,
) -> JointTrajectory:
    """plan_path, then verify_step; an IK branch switch along the way is refused (StepRefused) too."""
    try:
        trajectory = plan_path(arm, q_start, targets_at, pitch_at, yaw, duration_s, ramp_s, label, rate_hz)
    except DiscontinuousPath as error:
        raise StepRefused(f"the arm cannot follow the step continuously: {error}", "discontinuous") from error
    verify_step(arm, trajectory.positions_rad, axis, amount, tol_rad, follows_waist)
    return trajectory


def _plan_pitch(arm, q_start, start: GripperPose, amount: float, speeds: StepSpeeds, rate_hz: float):
    duration_s, ramp_s = _profile(abs(amount), speeds.angular_rad_s, speeds.angular_accel_rad_s2)

    def targets_at(s: np.ndarray) -> np.ndarray:
        return np.repeat(start.position_m[None, :], s.size, axis=0)

    def pitch_at(s: np.ndarray) -> np.ndarray:
        return start.pitch_rad + s * amount

    return _checked_path(arm, q_start, targets_at, pitch_at, None, duration_s, ramp_s, _step_text("pitch", amount), "pitch", amount, rate_hz)


def _plan_roll(arm, q_start, amount: float, speeds: StepSpeeds, rate_hz: float):
    q_goal = q_start.copy()
    q_goal[-1] += amount
    low, high = float(arm.lower_rad[-1]), float(arm.upper_rad[-1])
    if not low <= q_goal[-1] <= high:
        name = arm.joint_names[-1] if getattr(arm, "joint_names", None) else "the last joint"
        raise StepRefused(
            f"{_step_text('roll', amount)}: {name} would reach {math.degrees(q_goal[-1]):.1f}°, outside its limits "
            f"[{math.degrees(low):.0f}°, {math.degrees(high):.0f}°]",
            f"joint limit ({name})",
        )
    duration_s, _ = _profile(abs(amount), speeds.angular_rad_s, speeds.angular_accel_rad_s2)
    return plan_joint_move(q_start, q_goal, arm, moving_time_s=duration_s, rate_hz=rate_hz)


def verify_step(arm, positions_rad: np.ndarray, axis: str, amount: float, tol_rad: float = ORIENTATION_TOL_RAD,
                follows_waist: bool = False) -> None:
    """StepRefused unless every sample keeps the gripper on the asked motion (FK of the planned joints):
    Cartesian: on the line within POSITION_TOL_M, pitch and yaw within ORIENTATION_TOL_RAD of the start's,
    ending within POSITION_TOL_M of the goal; pitch: the point kept, ending at start + amount; roll: the
    point and the pitch kept. follows_waist (a Cartesian step that keeps the wrist roll): the yaw may turn
    with the waist, by what the waist's turn alone gives (the start's other joints with each sample's waist)."""
    poses = gripper_poses(arm, positions_rad)
    start, end = poses[0], poses[-1]
    if follows_waist:  # the yaw each sample's waist gives the start's gripper: the reference instead of the start's
        waist_only = np.repeat(np.asarray(positions_rad[:1], float), len(positions_rad), axis=0)
        waist_only[:, 0] = np.asarray(positions_rad, float)[:, 0]
        reference_yaws = [pose.yaw_rad for pose in gripper_poses(arm, waist_only)]
    else:
        reference_yaws = [start.yaw_rad] * len(poses)
    label = _step_text(axis, amount)
    direction = np.zeros(3)
    if axis in LINEAR_AXES:
        direction[LINEAR_AXES.index(axis)] = 1.0
    worst_off_m, worst_pitch, worst_yaw = 0.0, 0.0, 0.0
    for pose, reference_yaw in zip(poses, reference_yaws):
        offset = pose.position_m - start.position_m
        along = float(offset @ direction)
        worst_off_m = max(worst_off_m, float(np.linalg.norm(offset - along * direction)))
        if axis != "pitch":
            worst_pitch = max(worst_pitch, abs(angle_difference_rad(pose.pitch_rad, start.pitch_rad)))
        if axis in LINEAR_AXES:
            worst_yaw = max(worst_yaw, abs(angle_difference_rad(pose.yaw_rad, reference_yaw)))
    if axis in LINEAR_AXES:
        end_error_m = float(np.linalg.norm(end.position_m - (start.position_m + amount * direction)))
        worst_off_m = max(worst_off_m, end_error_m)
    if axis == "pitch":
        end_error = abs(angle_difference_rad(end.pitch_rad, start.pitch_rad + amount))
        if end_error > tol_rad:
            raise StepRefused(f"{label}: the pitch would end {math.degrees(end_error):.2f}° off", "orientation")
    if worst_off_m > POSITION_TOL_M:
        raise StepRefused(f"{label}: the gripper point would leave the asked motion by {worst_off_m * 1000:.1f} mm", "off the line")
    if worst_pitch > tol_rad:
        raise StepRefused(f"{label}: the gripper's pitch would change by {math.degrees(worst_pitch):.2f}°", "orientation")
    if axis in LINEAR_AXES and not follows_waist:
        waist_turn, roll = abs(positions_rad[-1][0] - positions_rad[0][0]), abs(positions_rad[-1][-1] - positions_rad[0][-1])
        if roll > MAX_ROLL_PER_WAIST * waist_turn + 1e-3:
            raise StepRefused(
                f"{label}: the waist turns {math.degrees(waist_turn):.2f}°, and holding the gripper's yaw would roll the "
                f"wrist {math.degrees(roll):.1f}° with the gripper tilted (pitch {math.degrees(start.pitch_rad):.1f}°): "
                "a 5-joint arm keeps its heading sideways only pointing (nearly) down; pitch it down first, or step along the arm",
                "orientation",
            )
    if worst_yaw > tol_rad:
        if follows_waist:
            raise StepRefused(f"{label}: the gripper's yaw would leave the waist's heading by {math.degrees(worst_yaw):.2f}°",
                              "orientation")
        raise StepRefused(
            f"{label}: the gripper's yaw would change by {math.degrees(worst_yaw):.2f}° (a 5-joint arm turns the gripper "
            "with the waist)",
            "orientation",
        )


def yaw_turn_rad(arm, positions_rad) -> float:
    """How much a planned motion turns the gripper's yaw, start to end (wrapped; a 5-joint arm's Cartesian step
    from a level or tilted gripper turns it with the waist)."""
    poses = gripper_poses(arm, np.asarray(positions_rad, float)[[0, -1]])
    return angle_difference_rad(poses[1].yaw_rad, poses[0].yaw_rad)
