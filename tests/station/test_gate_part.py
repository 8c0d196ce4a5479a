"""The motion gate as a part (station.gate, motion.py), built without a Station: the real RX200 model, a fast
simulated arm (MuJoCo's joint positions are the ground truth), a real latch and the simulation's clock. What it must
do alone: send only once the lock is released, refuse a start away from the arm and anything while latched or once
the job no longer owns the arm, follow the commanded reference on its clock, forget it on a halt, and pace at the
override."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import numpy as np
import pytest

from armlab.devices.arm import JointState, JointTrajectory
from armlab.errors import CommandRefused
from armlab.kinematics import load_arm
from armlab.motion.end_effector import end_effector
from armlab.motion.safety import UnsafeTrajectory
from armlab.motion.trajectory import plan_joint_move
from armlab.station.config import StationConfig
from armlab.station.jobs import Job, JobCancelled, JobContext
from armlab.station.latch import Latch
from armlab.station.motion import HandoverLate, MotionGate
from armlab.station.motion_record import MotionRecord
from armlab.station.states import State
from armlab.station.status import ArmReadings
from armlab.workcell.loading import load_workcell_motion_config

ARM = load_arm("rx200")
GOAL = np.array([0.4, -0.2, 0.3, 0.6, 0.2])


@pytest.fixture(scope="module")
def cell():
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=3))
    cell.start()
    for device in (cell.arm, cell.gripper):
        if not device.is_connected:
            device.connect()
    yield cell
    cell.close()


class Owner:
    """What core.Station injects as owns_arm: here a switch a test flips (the job no longer current)."""

    def __init__(self) -> None:
        self.current = True

    def __call__(self, ctx: JobContext) -> None:
        if not self.current:
            raise JobCancelled("job is no longer current")


@pytest.fixture()
def gate(cell):
    config = load_workcell_motion_config(StationConfig().workcell)
    owner = Owner()
    latch = Latch(cell.arm, cell.gripper, on_halt=lambda: gate.forget_commanded())
    gate = MotionGate(cell.arm, cell.gripper, ARM, latch, cell.clock, threading.RLock(), motion_config=lambda: config,
                      end_effector=lambda: end_effector("fingers"), held_block=lambda: None, state=lambda: State.IDLE,
                      owns_arm=owner, gripper_settle_timeout_s=1.0, moving_speed_rad_s=0.05)
    gate.owner = owner
    assert gate.wait_until(lambda: not cell.arm.is_moving(), 10.0)
    yield gate
    latch.halt_devices()
    gate.wait_motion(5.0)


def _move(gate, goal=GOAL, moving_time_s=1.0) -> JointTrajectory:
    return plan_joint_move(gate.start_position(), goal, ARM, moving_time_s=moving_time_s)


def _job() -> JobContext:
    return JobContext(Job(name="gate test"))


def test_a_command_reaches_the_arm_only_after_the_lock_is_released_and_the_arm_arrives(cell, gate):
    trajectory = _move(gate)
    with gate.sending():
        gate.command_arm(trajectory, gate.record.swept_box(trajectory))
        assert not cell.arm.is_moving()  # queued under the lock: the device has not been told yet
    assert cell.arm.is_moving()
    assert gate.wait_motion(10.0)
    assert np.abs(cell.arm_positions() - GOAL).max() < 0.02  # MuJoCo's joints, not the gate's idea of them


def test_a_device_command_outside_sending_is_refused():
    gate = MotionGate(None, None, ARM, Latch(None, None), None, threading.RLock(), motion_config=lambda: None,
                      end_effector=lambda: end_effector("fingers"), held_block=lambda: None, state=lambda: State.IDLE,
                      owns_arm=lambda ctx: None, gripper_settle_timeout_s=1.0, moving_speed_rad_s=0.05)
    with pytest.raises(RuntimeError, match="sending"):
        gate.send_later(lambda: None)


def test_a_trajectory_that_does_not_start_at_the_arm_is_refused_and_nothing_moves(cell, gate):
    elsewhere = plan_joint_move(gate.start_position() + np.array([0.3, 0, 0, 0, 0]), GOAL, ARM, moving_time_s=1.0)
    before = cell.arm_positions()
    with pytest.raises(UnsafeTrajectory), gate.sending():
        gate.command_arm(elsewhere, gate.record.swept_box(elsewhere))
    assert gate.commanded is None
    gate.wait_until(lambda: False, 0.3)
    assert not cell.arm.is_moving() and np.abs(cell.arm_positions() - before).max() < 1e-3


def test_nothing_is_sent_while_latched_and_a_halt_forgets_the_commanded_motion(cell, gate):
    trajectory = _move(gate, GOAL * 0.5)
    gate.latch.set()
    try:
        with pytest.raises(CommandRefused), gate.sending():
            gate.command_arm(trajectory, gate.record.swept_box(trajectory))
        assert not cell.arm.is_moving()
    finally:
        gate.latch.clear()
    with gate.sending():
        gate.command_arm(trajectory, gate.record.swept_box(trajectory))
    assert gate.commanded is not None
    gate.latch.halt_devices()
    assert gate.commanded is None and gate.commanded_joints_rad() is None


def test_a_job_that_no_longer_owns_the_arm_sends_nothing(cell, gate):
    gate.owner.current = False
    with pytest.raises(JobCancelled):
        gate.run_trajectory(_job(), _move(gate, GOAL * 0.3))
    assert gate.commanded is None and not cell.arm.is_moving()


def test_the_commanded_reference_follows_the_trajectory_on_the_gates_clock(cell, gate):
    trajectory = _move(gate, GOAL * 0.8, moving_time_s=2.0)
    with gate.sending():
        gate.command_arm(trajectory, gate.record.swept_box(trajectory))
    t0 = gate.commanded[1]
    gate.wait_until(lambda: False, 0.7)  # fast mode: the physics and the clock advance only while waited on
    elapsed = gate.clock_s() - t0
    assert 0.7 <= elapsed < trajectory.duration_s
    assert np.allclose(gate.commanded_joints_rad(), trajectory.sample(elapsed), atol=1e-9)
    assert gate.commanded_motion_running() and gate.arm_moving() == "the arm is moving"
    assert gate.wait_motion(10.0)
    gate.wait_until(lambda: False, 0.2)
    assert not gate.commanded_motion_running()


def test_a_job_step_runs_through_the_gate_paced_at_the_override(cell, gate):
    full = _move(gate, GOAL * -0.5, moving_time_s=None)
    gate.set_speed_percent(50.0)
    try:
        start = gate.clock_s()
        gate.run_trajectory(_job(), full)
        taken_s = gate.clock_s() - start
    finally:
        gate.set_speed_percent(100.0)
    sent = gate.commanded[0]
    assert sent.duration_s > 1.6 * full.duration_s  # half speed: about twice as long
    assert taken_s >= sent.duration_s
    assert np.abs(cell.arm_positions() - GOAL * -0.5).max() < 0.02


def test_a_motion_paced_at_an_override_changed_since_is_planned_again(gate):
    gate.set_speed_percent(40.0)
    try:
        with pytest.raises(HandoverLate):
            gate.pace_next_send(100.0)
        gate.pace_next_send(40.0)
    finally:
        gate.set_speed_percent(100.0)


def test_a_wait_times_out_on_the_simulated_clock_and_returns_at_once_when_latched(cell, gate):
    start = cell.sim_time_s
    assert gate.wait_until(lambda: False, 0.5) is False
    assert 0.5 <= cell.sim_time_s - start < 0.5 + 0.1
    gate.latch.set()
    try:
        start = cell.sim_time_s
        assert gate.wait_until(lambda: False, 30.0) is False
        assert cell.sim_time_s - start < 0.01
        with pytest.raises(JobCancelled):
            gate.wait_in_job(_job(), lambda: False, 30.0)
    finally:
        gate.latch.clear()


class PushedArm:
    """An arm at rest by its own word whose joints are pushed at a given speed (by hand, or falling limp)."""

    def __init__(self, speed_rad_s: float) -> None:
        self.speed_rad_s = speed_rad_s

    def read_joint_state(self) -> JointState:
        return JointState(np.zeros(5), np.array([0.0, self.speed_rad_s, 0.0, 0.0, 0.0]), 0.0)

    def is_moving(self) -> bool:
        return False


class StillGripper:
    def read_state(self):
        return SimpleNamespace(width_m=0.03, holding=False, command="release")


@pytest.mark.parametrize("speed_rad_s, moving", [(0.08, True), (0.03, False)])
def test_the_gate_and_the_status_count_the_same_arm_as_moving(speed_rad_s, moving):
    """One rule of 'the arm is moving' (status.arm_turning): the status' `moving` and the gate's arm_moving (which
    refuses a self-recalibration) agree on a joint pushed faster or slower than moving_speed_rad_s."""
    arm = PushedArm(speed_rad_s)
    gate = MotionGate(arm, None, ARM, Latch(arm, None), None, threading.RLock(), motion_config=lambda: None,
                      end_effector=lambda: end_effector("fingers"), held_block=lambda: None, state=lambda: State.IDLE,
                      owns_arm=lambda ctx: None, gripper_settle_timeout_s=1.0, moving_speed_rad_s=0.05)
    readings = ArmReadings(arm, StillGripper(), ARM, 0.05)
    assert readings.read()["moving"] is moving
    assert gate.arm_moving() == ("the arm is moving" if moving else None)


def test_the_record_tells_which_spots_a_motion_passed_since_a_time():
    now = {"s": 100.0}
    record = MotionRecord(ARM, wall_s=lambda: now["s"])
    trajectory = plan_joint_move(ARM.home_rad, GOAL, ARM, moving_time_s=1.0)
    end_m = ARM.fk(GOAL)[:3, 3]
    record.add(trajectory.duration_s, record.swept_box(trajectory))
    far_m = end_m + np.array([0.0, 0.0, 0.0]) - np.array([0.0, 2.0 * np.sign(end_m[1] or 1.0), 0.0])
    assert record.moved_over_since(end_m, since_s=100.5) and not record.moved_over_since(far_m, since_s=100.5)
    assert not record.moved_over_since(end_m, since_s=100.0 + trajectory.duration_s + 0.1)  # seen after it ended
    assert record.changed_at_since(end_m, since_s=100.5)  # the gripper came down to it
    assert not record.changed_at_since(end_m - np.array([0.0, 0.0, 0.15]), since_s=100.5)  # it passed high above: unchanged
    now["s"] = 200.0
    record.note_change_everywhere()
    assert record.changed_at_since(far_m, since_s=150.0) and not record.changed_at_since(far_m, since_s=250.0)
