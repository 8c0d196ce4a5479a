"""Hold-to-run Cartesian jog: the gripper point moves along a world axis (x, y or z) while the jog is held,
keeping its pitch and yaw (an arm with six joints or more: the tool's whole orientation), and stops by itself.

The motion along the line is the joint jog's 1-D hold-to-run profile (armlab.motion.jog.plan_jog) on the
distance along the axis, in metres: it ramps to the asked speed within the jog's linear acceleration, holds
it for hold_s, then brakes to rest. Every sample is solved by IK on the jog's line, which is anchored where the
jog began (its point, pitch and yaw), so the re-plan of each heartbeat does not drift off it. Where the line
cannot go on (out of reach, a joint limit, IK changing branch, a joint faster than its limit, or the caller's
own check: the board, the arm against itself), the profile is planned again with that place as its end, so the
arm brakes to rest before it and never jumps branches; the plan says why (`stopped_by`). Pure: no devices.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.kinematics.errors import Unreachable
from armlab.motion.errors import StepRefused
from armlab.motion.jog import plan_jog
from armlab.motion.pose_path import holds_full_pose
from armlab.motion.retime import MAX_SAMPLE_STEP_RAD

AXES = ("x", "y", "z")
BOUNDARY_MARGIN_M = 0.002  # braking for a boundary stops this far before the last sample that passed
OPEN_LINE_M = 1e3  # "no boundary" for the 1-D profile
MAX_BOUNDARY_PASSES = 4  # re-plans with a nearer end before the jog is refused
MOVES_M = 5e-4  # a plan that carries the gripper point less than this along the line does not move it
# A 5-joint arm holds the gripper's yaw by rolling the wrist only while it points (nearly) down (pitch 53-127°,
# as the jog steps: armlab.motion.gripper_step); elsewhere it keeps the wrist roll and the yaw turns with the waist.
HOLD_YAW_PITCH_RAD = (math.radians(53.0), math.radians(127.0))

# first_unsafe(trajectory) -> (index of the first sample that fails, reason) or None: the caller's checks.
FirstUnsafe = Callable[[JointTrajectory], "tuple[int, str] | None"]


@dataclass(frozen=True)
class JogLine:
    """The line a Cartesian jog moves on: from origin_m (world, metres) along the unit world axis, with the
    gripper's pitch_rad and yaw_rad held (yaw_rad None: the wrist roll is kept instead) or, for an arm that holds
    a full pose, the tool rotation (3, 3)."""

    axis: str
    origin_m: np.ndarray
    pitch_rad: float
    yaw_rad: float | None
    rotation: np.ndarray | None = None

    @property
    def direction(self) -> np.ndarray:
        unit = np.zeros(3)
        unit[AXES.index(self.axis)] = 1.0
        return unit

    def distance_m(self, arm, q_rad) -> float:
        """How far along the line the gripper point is at q (its projection on the line)."""
        point = np.asarray(arm.fk(np.asarray(q_rad, float)), float)[:3, 3]
        return float((point - self.origin_m) @ self.direction)

    def speed_m_s(self, arm, q_rad, qdot_rad_s, dt_s: float) -> float:
        """The gripper point's speed along the line at q moving at qdot: the distance covered over the last dt_s."""
        q = np.asarray(q_rad, float)
        return (self.distance_m(arm, q) - self.distance_m(arm, q - np.asarray(qdot_rad_s, float) * dt_s)) / dt_s

    def points_m(self, distances_m: np.ndarray) -> np.ndarray:
        """World points (N, 3) at these distances along the line."""
        return self.origin_m[None, :] + np.asarray(distances_m, float)[:, None] * self.direction[None, :]


def jog_line(arm, q_rad, axis: str) -> JogLine:
    """The line of a jog along `axis` starting at the arm's pose q_rad (InvalidInput for another axis)."""
    if axis not in AXES:
        raise InvalidInput(f"axis must be one of {', '.join(AXES)}, got {axis!r}")
    q = np.asarray(q_rad, float)
    T = np.asarray(arm.fk(q), float)
    if holds_full_pose(arm):
        return JogLine(axis, T[:3, 3].copy(), 0.0, None, T[:3, :3].copy())
    pitch = float(arm.pitch_of(q))
    closing = T[:3, 1]
    pointing_down = HOLD_YAW_PITCH_RAD[0] <= pitch <= HOLD_YAW_PITCH_RAD[1]
    yaw = math.atan2(float(closing[1]), float(closing[0])) if pointing_down else None
    return JogLine(axis, T[:3, 3].copy(), pitch, yaw)


def solve_line(arm, line: JogLine, q_start, distances_m: np.ndarray) -> tuple[np.ndarray, int | None, str | None]:
    """IK of the line's points at distances_m (N,), the first row being q_start: (joints (N, dof), the index of
    the first sample that cannot be reached continuously or None, why). Rows from that index on are not valid."""
    q_start = np.asarray(q_start, float)
    points = line.points_m(distances_m)
    count = len(points)
    positions = np.repeat(q_start[None, :], count, axis=0)
    if count < 2:
        return positions, None, None
    if line.rotation is not None:
        poses = np.repeat(np.eye(4)[None], count - 1, axis=0)
        poses[:, :3, :3] = line.rotation
        poses[:, :3, 3] = points[1:]
        solved, ok = arm.ik_pose_batch(poses, q_seed=q_start)

        def one(index: int, seed: np.ndarray) -> np.ndarray:
            return arm.ik_pose(poses[index - 1], q_seed=seed)
    else:
        solved, ok = arm.ik_batch(points[1:], pitch=line.pitch_rad, yaw=line.yaw_rad, q_seed=q_start)

        def one(index: int, seed: np.ndarray) -> np.ndarray:
            return arm.ik(points[index], pitch=line.pitch_rad, yaw=line.yaw_rad, q_seed=seed)
    positions[1:] = np.where(np.asarray(ok)[:, None], np.asarray(solved, float), np.nan)
    names = list(getattr(arm, "joint_names", [])) or [f"joint {j}" for j in range(len(q_start))]
    for index in range(1, count):
        step = np.abs(positions[index] - positions[index - 1])
        if np.all(np.isfinite(step)) and step.max() <= MAX_SAMPLE_STEP_RAD:
            continue
        try:  # the batch missed it or took another branch: seeded with the previous sample
            positions[index] = one(index, positions[index - 1])
        except Unreachable as error:
            return positions, index, str(error)
        step = np.abs(positions[index] - positions[index - 1])
        if step.max() > MAX_SAMPLE_STEP_RAD:
            joint = int(np.argmax(step))
            where = ", ".join(f"{v * 1000:.1f}" for v in points[index])
            return positions, index, f"{names[joint]} would jump {step[joint]:.3f} rad at ({where}) mm (IK changed branch)"
    return positions, None, None


@dataclass(frozen=True)
class CartesianJogPlan:
    """A planned Cartesian jog: the joint trajectory, the distance along the line of each sample (metres), and why
    the line cannot go on past where it brakes (None: it brakes because the hold ends)."""

    trajectory: JointTrajectory
    distances_m: np.ndarray
    stopped_by: str | None

    @property
    def travel_m(self) -> float:
        return float(np.max(np.abs(self.distances_m - self.distances_m[0])))


def plan_cartesian_jog(
    arm,
    line: JogLine,
    q0_rad,
    v0_m_s: float,
    v_target_m_s: float,
    hold_s: float,
    accel_m_s2: float,
    rate_hz: float = 100.0,
    first_unsafe: FirstUnsafe | None = None,
) -> CartesianJogPlan:
    """A hold-to-run jog along `line` from the arm at q0_rad moving at v0_m_s along it: reaches v_target_m_s
    (signed, metres per second along the axis) within accel_m_s2, keeps it until hold_s, then brakes to rest;
    braking earlier, BOUNDARY_MARGIN_M before the first sample the line cannot be followed to (IK, branch,
    joint speed, first_unsafe). StepRefused with the reason when no such plan is found in MAX_BOUNDARY_PASSES."""
    q0 = np.asarray(q0_rad, float)
    s0 = line.distance_m(arm, q0)
    low, high = s0 - OPEN_LINE_M, s0 + OPEN_LINE_M
    velocity_limit = np.asarray(arm.velocity_limit_rad_s, float)
    reason = None
    for _ in range(MAX_BOUNDARY_PASSES):
        profile = plan_jog([s0], [v0_m_s], [v_target_m_s], hold_s, [low], [high], [accel_m_s2], rate_hz, margin=0.0)
        distances, times = profile.positions_rad[:, 0], profile.times_s
        positions, bad, why = solve_line(arm, line, q0, distances)
        if bad is None:
            speeds = np.abs(np.diff(positions, axis=0)) * rate_hz
            fast = np.argwhere(speeds > velocity_limit[None, :])
            if fast.size:
                sample, joint = (int(v) for v in fast[0])
                bad, why = sample + 1, f"{arm.joint_names[joint]} would pass its velocity limit (near a singularity)"
        if bad is None and first_unsafe is not None:
            found = first_unsafe(JointTrajectory(times, positions))
            if found is not None:
                bad, why = max(1, found[0]), found[1]
        if bad is None:
            return CartesianJogPlan(JointTrajectory(times, positions), distances, reason)
        reason = why
        last_good_m = float(distances[bad - 1])
        if distances[bad] >= distances[bad - 1]:
            high = min(high, last_good_m - BOUNDARY_MARGIN_M)
        else:
            low = max(low, last_good_m + BOUNDARY_MARGIN_M)
    raise StepRefused(f"the {line.axis} jog cannot go on along its line: {reason}", "boundary")
