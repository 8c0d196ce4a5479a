"""A jog that takes over a move in the move's last samples continues the command (issue 18 item 1)."""

from __future__ import annotations

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.kinematics import load_arm
from armlab.motion.blend import arm_limits
from armlab.motion.handover import splice, take_over
from armlab.motion.jog import plan_jog
from armlab.motion.measure import motion_figures
from armlab.motion.trajectory import plan_joint_move

ARM = load_arm("rx200")
RATE_HZ = 100.0


def followed_accel_ratio(trajectory, tick_s: float = 0.004) -> float:
    """The command's peak acceleration (x the limit) as the servos follow it: linear between samples at each tick."""
    ticks = np.arange(0.0, trajectory.duration_s + 0.05, tick_s)
    reference = np.column_stack([np.interp(ticks, trajectory.times_s, trajectory.positions_rad[:, j]) for j in range(ARM.dof)])
    trace = {"time_s": ticks, "reference_rad": reference, "velocity_rad_s": np.zeros_like(reference)}
    return motion_figures(trace).ratio(ARM.accel_limit_rad_s2)[0]


def test_a_jog_back_taking_over_in_a_moves_last_sample_keeps_within_the_acceleration_limit():
    """A move decelerating at the limit ends with a sample segment still moving (a·h/2); a jog back planned as from
    rest there stepped the command by 1.5 a·h at the splice (1.2x the limit over 20 ms, bench seed 2)."""
    move = plan_joint_move(np.zeros(5), np.array([0.0, 0.0, 0.0, 0.0, -0.4]), ARM)
    limits = arm_limits(ARM)
    worst = 0.0
    for before_end_s in (0.001, 0.004, 0.008, 0.012, 0.016):
        handover = take_over(move, 0.0, move.duration_s - before_end_s, 0.02, RATE_HZ)
        assert handover is not None
        jog = plan_jog(handover.position_rad, handover.segment_velocity_rad_s, np.array([0.0, 0.0, 0.0, 0.0, 0.8]), 0.2,
                       ARM.lower_rad, ARM.upper_rad, limits.accel_rad_s2, RATE_HZ)
        command = splice(handover, jog)
        worst = max(worst, followed_accel_ratio(command))
    assert worst <= 1.0 + 1e-9, f"the spliced command reaches {worst:.3f}x the acceleration limit"


def test_a_jog_back_just_after_a_move_ended_keeps_within_the_acceleration_limit():
    """The move ended less than a sample ago: its last segment still moved, and a jog from rest starting at once
    stepped the command by 1.5 a·h (1.2x over 20 ms, bench seed 2): the handover holds the last sample first."""
    move = plan_joint_move(np.zeros(5), np.array([0.0, 0.0, 0.0, 0.0, -0.4]), ARM)
    accel = arm_limits(ARM).accel_rad_s2
    back = np.array([0.0, 0.0, 0.0, 0.0, 0.8])
    worst = 0.0
    for after_end_s in (0.0, 0.002, 0.006, 0.0099):
        now_s = move.duration_s + after_end_s
        handover = take_over(move, 0.0, now_s, 0.02, RATE_HZ)
        if handover is None:  # the gate plans from rest at the last sample, starting now
            jog = plan_jog(move.positions_rad[-1], np.zeros(5), back, 0.2, ARM.lower_rad, ARM.upper_rad, accel, RATE_HZ)
            times = np.concatenate([move.times_s, now_s + jog.times_s[1:] if after_end_s == 0.0 else now_s + jog.times_s])
            positions = np.vstack([move.positions_rad, jog.positions_rad[1:] if after_end_s == 0.0 else jog.positions_rad])
        else:
            jog = plan_jog(handover.position_rad, handover.segment_velocity_rad_s, back, 0.2, ARM.lower_rad, ARM.upper_rad,
                           accel, RATE_HZ)
            command = splice(handover, jog)
            kept = move.times_s < handover.planned_at_s - 1e-12
            times = np.concatenate([move.times_s[kept], handover.planned_at_s + command.times_s])
            positions = np.vstack([move.positions_rad[kept], command.positions_rad])
        worst = max(worst, followed_accel_ratio(JointTrajectory(times, positions)))
    assert worst <= 1.0 + 1e-9, f"the command reaches {worst:.3f}x the acceleration limit"
