"""The last check before a plan reaches the arm: joint limits, speed limits, the board surface, the
workspace box and the size of one step.

check_trajectory rejects any trajectory in which a joint leaves its position limits, exceeds its
velocity or acceleration limit (finite differences of the samples), jumps more than max_step_rad between
two samples, or any link point (each joint origin and the gripper point, world frame) goes below the
board surface plus a clearance or leaves the workspace box. Links are straight segments between those
points, so checking the points checks the links (the box is convex). check_start rejects a trajectory
whose first sample is not where the arm is. Pure: no device calls.
"""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput, PlanRefused

# Relative tolerance on velocity/acceleration limits (finite differences of a plan exactly at the limit).
LIMIT_RTOL = 1e-6
# Absolute tolerance on position limits, radians (a measured start may sit a hair outside).
POSITION_TOL_RAD = 1e-9


class UnsafeTrajectory(PlanRefused):
    """A trajectory violates a joint limit or goes below the board; the message names joint/point and time,
    `part` the joint or part of the arm alone (None when the check names none) and `at_q_rad` the joints at the
    offending sample (None when the check has none), so a 3-D view can draw the arm there with the part in red."""

    def __init__(self, message: str, part: str | None = None, at_q_rad=None) -> None:
        super().__init__(message)
        self.part = part
        self.at_q_rad = None if at_q_rad is None else [float(v) for v in np.asarray(at_q_rad, dtype=float).ravel()]


def _joint_name(arm, index: int) -> str:
    names = getattr(arm, "joint_names", None)
    return names[index] if names is not None and index < len(names) else f"joint {index}"


def _point_name(arm, index: int, point_count: int) -> str:
    if index == point_count - 1:
        return "gripper point"
    return f"{_joint_name(arm, index)} origin"


def finite_difference_rates(trajectory: JointTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """Velocity (N-1, dof) between samples and acceleration (N-2, dof) at interior samples."""
    times, positions = trajectory.times_s, trajectory.positions_rad
    dt = np.diff(times)
    velocity = np.diff(positions, axis=0) / dt[:, None]
    if positions.shape[0] < 3:
        return velocity, np.zeros((0, positions.shape[1]))
    mid_dt = 0.5 * (dt[1:] + dt[:-1])
    accel = np.diff(velocity, axis=0) / mid_dt[:, None]
    return velocity, accel


def check_start(trajectory: JointTrajectory, q_measured_rad, tolerance_rad: float, names=None) -> None:
    """UnsafeTrajectory if the first sample is more than tolerance_rad from the measured joints (the arm
    would jump to it at the servos' full speed)."""
    first = trajectory.positions_rad[0]
    q = np.asarray(q_measured_rad, dtype=float)
    error = np.abs(first - q)
    joint = int(np.argmax(error))
    if error[joint] > tolerance_rad:
        name = names[joint] if names is not None and joint < len(names) else f"joint {joint}"
        raise UnsafeTrajectory(
            f"the trajectory starts {error[joint]:.3f} rad from where {name} is (more than {tolerance_rad:.3f} rad): "
            "the arm would jump; plan from the measured position", part=name
        )


def check_trajectory(
    arm,
    trajectory: JointTrajectory,
    clearance_m: float = 0.0,
    board_z_m: float = 0.0,
    check_rates: bool = True,
    workspace_m: tuple | None = None,
    max_step_rad: float | None = None,
) -> None:
    """Raise UnsafeTrajectory if the trajectory is not safe to send to `arm`; return None if it is.

    arm: a kinematics model (lower_rad, upper_rad, velocity_limit_rad_s, accel_limit_rad_s2, dof,
    joint_frames(q) -> (dof+1, 4, 4) world frames). clearance_m: how far above the board (z =
    board_z_m in the world frame) every link point must stay. check_rates: also check velocity and
    acceleration by finite differences (off for trajectories that do not start/end at rest on purpose).
    workspace_m: ((xmin, ymin, zmin), (xmax, ymax, zmax)) world box every link point must stay in (None:
    no box). max_step_rad: the largest change of any joint between two samples (None: unchecked).
    """
    positions = trajectory.positions_rad
    times = trajectory.times_s
    dof = int(arm.dof)
    if positions.shape[1] != dof:
        raise UnsafeTrajectory(f"trajectory has {positions.shape[1]} joints, the arm has {dof}")
    if not np.isfinite(clearance_m) or not np.isfinite(board_z_m):
        raise InvalidInput("clearance_m and board_z_m must be finite")

    lower, upper = np.asarray(arm.lower_rad, float), np.asarray(arm.upper_rad, float)
    below = positions < lower[None, :] - POSITION_TOL_RAD
    above = positions > upper[None, :] + POSITION_TOL_RAD
    bad = np.argwhere(below | above)
    if bad.size:
        sample, joint = (int(v) for v in bad[0])
        raise UnsafeTrajectory(
            f"{_joint_name(arm, joint)} = {positions[sample, joint]:.4f} rad at t = {times[sample]:.3f} s is outside "
            f"its limits [{lower[joint]:.4f}, {upper[joint]:.4f}]", part=_joint_name(arm, joint), at_q_rad=positions[sample]
        )

    if max_step_rad is not None and positions.shape[0] > 1:
        steps = np.abs(np.diff(positions, axis=0))
        jumps = np.argwhere(steps > max_step_rad)
        if jumps.size:
            sample, joint = (int(v) for v in jumps[0])
            raise UnsafeTrajectory(
                f"{_joint_name(arm, joint)} jumps {steps[sample, joint]:.3f} rad between samples at t = {times[sample]:.3f} s "
                f"(at most {max_step_rad:.3f} rad per step)", part=_joint_name(arm, joint)
            )

    if check_rates:
        velocity, accel = finite_difference_rates(trajectory)
        velocity_limit = np.asarray(arm.velocity_limit_rad_s, float)
        accel_limit = np.asarray(arm.accel_limit_rad_s2, float)
        too_fast = np.argwhere(np.abs(velocity) > velocity_limit[None, :] * (1.0 + LIMIT_RTOL))
        if too_fast.size:
            sample, joint = (int(v) for v in too_fast[0])
            raise UnsafeTrajectory(
                f"{_joint_name(arm, joint)} moves at {abs(velocity[sample, joint]):.3f} rad/s at t = {times[sample]:.3f} s, "
                f"above its velocity limit {velocity_limit[joint]:.3f} rad/s", part=_joint_name(arm, joint)
            )
        too_sharp = np.argwhere(np.abs(accel) > accel_limit[None, :] * (1.0 + LIMIT_RTOL))
        if too_sharp.size:
            sample, joint = (int(v) for v in too_sharp[0])
            raise UnsafeTrajectory(
                f"{_joint_name(arm, joint)} accelerates at {abs(accel[sample, joint]):.3f} rad/s² at "
                f"t = {times[sample + 1]:.3f} s, above its acceleration limit {accel_limit[joint]:.3f} rad/s²",
                part=_joint_name(arm, joint),
            )

    floor_z = board_z_m + clearance_m
    points = _link_points(arm, positions)  # (N, points, 3)
    radii = point_radii_m(arm, points.shape[1])
    # The links' undersides (a straight link is lowest at an end); a link may rest on the board (the sleep pose lays
    # the wrist on it, 0.0 mm), not press into it.
    heights = points[:, :, 2] - radii[None, :] + np.where(radii > 0.0, LINK_REST_TOLERANCE_M, 0.0)[None, :]
    heights = excuse_a_resting_start(heights, floor_z, applies=radii > 0.0)
    heights[:, 0] = np.inf  # the first joint's origin is fixed to the base (the UR3's stands on the board at z = 0)
    sample, point = np.unravel_index(int(np.argmin(heights)), heights.shape)
    if heights[sample, point] < floor_z:
        first = int(np.flatnonzero(np.min(heights, axis=1) < floor_z)[0])  # earliest offending sample
        point = int(np.argmin(heights[first]))
        what = _point_name(arm, point, heights.shape[1])
        if radii[point] > 0.0:
            what = f"the link at the {what} ({radii[point] * 1000:.0f} mm thick around it)"
        raise UnsafeTrajectory(
            f"{what} at z = {heights[first, point] * 1000:.1f} mm at "
            f"t = {times[first]:.3f} s is below the board surface + clearance ({floor_z * 1000:.1f} mm)",
            part=_point_name(arm, point, heights.shape[1]), at_q_rad=positions[first],
        )
    if workspace_m is not None:
        low, high = (np.asarray(corner, dtype=float) for corner in workspace_m)
        outside = np.any((points < low - 1e-9) | (points > high + 1e-9), axis=2)  # (N, points)
        if outside.any():
            sample, point = (int(v) for v in np.argwhere(outside)[0])
            where = ", ".join(f"{axis} = {value * 1000:.0f} mm" for axis, value in zip("xyz", points[sample, point]))
            raise UnsafeTrajectory(
                f"{_point_name(arm, point, points.shape[1])} at ({where}) at t = {times[sample]:.3f} s leaves the workspace box "
                f"{np.round(low * 1000).astype(int).tolist()}..{np.round(high * 1000).astype(int).tolist()} mm"
            )


def excuse_a_resting_start(heights_m: np.ndarray, floor_m: float, applies=True) -> np.ndarray:
    """Heights (N, ...) of a part per sample of a motion, every sample but the last raised by how far below floor_m
    the first one is (where `applies`): a part that starts on or in the board (an arm let down limp onto it) may move
    out, never further in; where the motion ends (a target, a waypoint: a standing pose is [q, q]) must be clear."""
    heights = np.array(heights_m, dtype=float)
    heights[:-1] -= np.where(applies, np.minimum(heights[0] - floor_m, 0.0), 0.0)
    return heights


LINK_REST_TOLERANCE_M = 0.0005  # how far a link's underside may read below the board and still rest on it


def point_radii_m(arm, point_count: int) -> np.ndarray:
    """How far each of _link_points' points must keep from the board: the radius of the thicker of the two links
    meeting there (arm.link_radii_m: joint i's link runs from its origin to the next point), 0 without radii."""
    links = np.asarray(getattr(arm, "link_radii_m", np.zeros(point_count - 1)), dtype=float)
    radii = np.zeros(point_count)
    radii[: len(links)] = links
    radii[1 : len(links) + 1] = np.maximum(radii[1 : len(links) + 1], links)
    return radii


def _link_points(arm, positions: np.ndarray) -> np.ndarray:
    """World positions (N, dof+1, 3) of every joint origin and the gripper point at each sample (batched when the model can)."""
    frames = np.asarray(arm.joint_frames(positions))
    if frames.ndim == 4 and frames.shape[0] == positions.shape[0]:
        return frames[:, :, :3, 3]
    return np.array([np.asarray(arm.joint_frames(q))[:, :3, 3] for q in positions])
