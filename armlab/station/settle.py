"""A job's step ends with the arm where it was sent: MotionGate.run_trajectory waits for its arrival after the
trajectory's end time, and before the arm's position is used (a grasp, a release, a sighting of the gripper:
MotionGate.settle_arm) its unloaded joints are settled.

On the real RX200 the servos run P-only (the firmware's I and feed-forward gains are 0):
- arrival: the waist trails a fast long swing (0.03 rad after 2.9 rad, more loaded); the step waits until the arm
  stands within half the start tolerance of where the command holds it, or has stopped (a contact);
- settling: a joint gravity does not load (the waist; wrist_rotate and wrist_angle with the gripper pointing down)
  is held by its servo against the link's friction alone. After a short fast move the waist still swings when the
  step returns (2.9 deg 0.1 s after the end of a 16 deg turn) and stands up to ~0.2 deg short of its goal once
  still: 6 mm at the gripper 300 mm out (bench/arm_accuracy.py's worst point). Real arm software corrects from the
  joint readings: wait until those joints stand still, and move each one's command by minus what its reading
  still misses, at most SETTLE_CORRECTIONS times (an integral step the firmware does not take). Only where the
  position is used: after every step it cost pick_sort L3 seed 0 18 s simulated of its 120 (99 settlings).
The ideal arm stands at its command at the end time: neither wait nor correction costs it anything.
"""

from __future__ import annotations

import numpy as np

from armlab.kinematics.arm_calibration import ArmCalibrationError
from armlab.motion import plan_joint_move

ARRIVE_TIMEOUT_S, ARRIVED_SPEED_RAD_S = 1.0, 0.02  # stopped short of arriving: slower than this (a contact)
UNLOADED_NM = 0.01  # gravity's torque about a joint below this: its servo's steady error is under one encoder count
SETTLE_DEADBAND_RAD = 0.002  # a reading within this of its command is left alone (an encoder count is 0.0015 rad)
SETTLE_MAX_RAD = 0.02  # further off than this, something holds the joint (a contact, a push): not corrected
SETTLE_CORRECTIONS = 2
STILL_S, STILL_RAD = 0.05, 0.001  # still: the readings moved less than this (under one count) for this long
SETTLE_TIMEOUT_S = 1.5  # the most a step waits for its joints to stand still (the waist rings ~0.5 s)
CORRECTION_TIME_S = 0.15  # a correction's move (under 0.02 rad)


def arrived(gate, command_rad: np.ndarray) -> bool:
    """The arm stands within half the start tolerance of where command_rad holds it, or has stopped (a contact)."""
    state = gate.arm.read_joint_state()
    here = gate.holding_command(state.position_rad)
    if float(np.abs(here - command_rad).max()) <= 0.5 * gate.motion_config().start_tolerance_rad:
        return True
    return float(np.abs(state.velocity_rad_s).max()) < ARRIVED_SPEED_RAD_S


def unloaded_joints(model, q_rad: np.ndarray) -> np.ndarray:
    """Indices of the joints gravity hardly loads at q_rad (friction, not the arm's weight, decides where they stop)."""
    torques = getattr(model, "gravity_torques", None)
    try:
        return np.array([0]) if torques is None else np.flatnonzero(np.abs(np.asarray(torques(q_rad), float)) < UNLOADED_NM)
    except ArmCalibrationError:  # no load model for this arm (outside the RX200 family, e.g. the UR3): the waist
        return np.array([0])


def settle_at_rest(gate, ctx) -> int:
    """settle() toward the last step's end, once it has run (nothing while a motion runs, or in a job's cleanup). A
    correction's own end is not a target: the step's end it corrected toward stays one until the next step."""
    running = gate.commanded
    if running is None or ctx.in_cleanup or gate.commanded_motion_running():
        return 0
    settled = gate.settled_toward  # (the last correction's command id, the step's end it corrected toward)
    target = settled[1] if settled is not None and settled[0] == running[2] else running[0].positions_rad[-1]
    count = settle(gate, ctx, target)
    gate.settled_toward = (gate.commanded[2], target)
    return count


def settle(gate, ctx, target_rad: np.ndarray) -> int:
    """After a step to target_rad (at rest there): wait until its unloaded joints stand still and correct their
    commands from the readings (see the module). Returns how many corrections it sent."""
    joints = unloaded_joints(gate.model, target_rad)
    if not joints.size:
        return 0
    state = gate.arm.read_joint_state()
    miss = _miss(gate, target_rad, state.position_rad, joints)
    if np.abs(miss).max() <= SETTLE_DEADBAND_RAD and np.all(np.abs(state.velocity_rad_s[joints]) < ARRIVED_SPEED_RAD_S):
        return 0  # there, and not swinging through
    command = np.asarray(target_rad, float)
    for count in range(SETTLE_CORRECTIONS + 1):
        gate.wait_in_job(ctx, _still_check(gate, joints), SETTLE_TIMEOUT_S)
        miss = _miss(gate, target_rad, gate.joints_rad(), joints)
        # within the deadband: done; beyond SETTLE_MAX_RAD something holds the joint (a contact, a push): not ours
        if not SETTLE_DEADBAND_RAD < np.abs(miss).max() <= SETTLE_MAX_RAD or count == SETTLE_CORRECTIONS:
            return count
        goal = command.copy()  # from the command holding the arm (not its readings: the loaded joints droop below it)
        goal[joints] -= np.where(np.abs(miss) > SETTLE_DEADBAND_RAD, miss, 0.0)
        step = plan_joint_move(command, goal, gate.model, moving_time_s=CORRECTION_TIME_S,
                               rate_hz=gate.motion_config().sample_rate_hz)
        gate.start_trajectory(ctx, step)
        command = goal
        gate.wait_in_job(ctx, lambda: not gate.arm.is_moving(), step.duration_s + 1.0)
    return SETTLE_CORRECTIONS


def _miss(gate, target_rad: np.ndarray, reading_rad: np.ndarray, joints: np.ndarray) -> np.ndarray:
    """Where the command holding the joints now misses the target (rad, per joint)."""
    return (gate.holding_command(reading_rad) - np.asarray(target_rad, float))[joints]


def _still_check(gate, joints: np.ndarray):
    """A fresh predicate, true once the joints' readings stayed within STILL_RAD, their velocities reading under
    ARRIVED_SPEED_RAD_S, for STILL_S (motion clock): the velocities rule out the turn of a swing, where the position
    alone stands still that long (the waist swings at ~2 Hz)."""
    still = {"at": None, "since": gate.clock_s()}

    def is_still() -> bool:
        state, now = gate.arm.read_joint_state(), gate.clock_s()
        here = np.asarray(state.position_rad, float)[joints]
        moving = np.abs(np.asarray(state.velocity_rad_s, float)[joints]).max() >= ARRIVED_SPEED_RAD_S
        if still["at"] is None or moving or np.abs(here - still["at"]).max() > STILL_RAD:
            still["at"], still["since"] = here, now
            return False
        return now - still["since"] >= STILL_S

    return is_still
