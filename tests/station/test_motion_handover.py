"""Issue 18 item 1: a motion that replaces a running one continues it (position, velocity, acceleration) within
the acceleration limit, from every source: manual moves (REST and websocket call these), the jog, a job
started while the arm moves (it brakes first) and a job's own trajectory (the gate refuses one that would
not continue the motion). Measured on the simulation's clock at every control tick (fast, synchronous sim)."""

from __future__ import annotations

import threading

import numpy as np

from armlab import skills
from armlab.devices.arm import JointTrajectory
from armlab.errors import ArmMoving
from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures
from armlab.store import Waypoint
from station_helpers import at_rest

ARM = load_arm("rx200")
ACCEL = np.asarray(ARM.accel_limit_rad_s2, dtype=float)
# A legal plan's measured joints follow its command through the simulated servos' tracking within a few per cent
# (test_servo_tracking.py; 1.04x at most here): before the servos fed the acceleration forward they overshot it (a lone
# trapezoid: 1.14x; a jog, whose acceleration switches sign at once: 1.4x; 1.5x was allowed here); a move planned from
# rest while the waist turns at 3 rad/s measured 22x.
MEASURED_MAX = 1.05
STEP_MAX_RAD = 1e-3  # smooth motion changes by ~1e-4 rad from one 4 ms tick to the next



def _figures(cell, during_s: float):
    cell.step(during_s)
    return motion_figures(cell.stop_joint_recording())


def _assert_continuous(figures) -> None:
    command, measured = figures.ratio(ACCEL)
    assert command <= 1.01, f"the command accelerates at {command:.2f}x the limit"
    assert measured <= MEASURED_MAX, f"the joints accelerate at {measured:.2f}x the limit"
    assert figures.step_rad.max() < STEP_MAX_RAD, f"the command jumps {figures.step_rad.max():.4f} rad"


def test_a_move_sent_while_the_waist_turns_continues_its_motion(fast):
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    station.move_joints([1.5, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.8)  # the waist turns at ~3 rad/s
    assert station.arm.read_joint_state().velocity_rad_s[0] > 2.5
    cell.start_joint_recording()
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0])  # reverse
    _assert_continuous(_figures(cell, 2.5))
    assert not station.arm.is_moving() and abs(station.joints_rad()[0] + 1.0) < 0.01


def test_a_takeover_that_reaches_the_arm_late_continues_the_same_curve(fast, monkeypatch):
    """A CPU-starved send: the physics runs on 50 ms (simulated) between the station's send and the arm taking the
    command. The arm samples the splice at its own clock minus the start the station gave, so the reversal
    stays within the limit (before: the arm started the splice 50 ms late, shifted back, at 9x the limit)."""
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    station.move_joints([1.5, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.8)  # the waist turns at ~3 rad/s
    command_trajectory = cell.arm.command_trajectory

    def late(*args, **kwargs):
        cell.step(0.05)  # the physics (and the running move) goes on before the command gets the physics lock
        return command_trajectory(*args, **kwargs)

    monkeypatch.setattr(cell.arm, "command_trajectory", late)
    cell.start_joint_recording()
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0])  # reverse, sent late
    monkeypatch.undo()
    _assert_continuous(_figures(cell, 2.5))
    assert not station.arm.is_moving() and abs(station.joints_rad()[0] + 1.0) < 0.01


def test_a_move_from_rest_that_reaches_the_arm_late_is_then_taken_over_continuously(fast, monkeypatch):
    """A move from rest sent late starts late (from rest nothing jumps) and the station follows the arm's start:
    a takeover planned from it then continues the curve the arm really runs."""
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    command_trajectory = cell.arm.command_trajectory

    def late(*args, **kwargs):
        cell.step(0.05)
        return command_trajectory(*args, **kwargs)

    monkeypatch.setattr(cell.arm, "command_trajectory", late)
    cell.start_joint_recording()
    station.move_joints([1.5, 0.0, 0.0, 0.0, 0.0])  # from rest, sent late
    monkeypatch.undo()
    cell.step(0.8)
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0])  # reverse, sent at once
    _assert_continuous(_figures(cell, 2.5))
    assert not station.arm.is_moving() and abs(station.joints_rad()[0] + 1.0) < 0.01


def test_a_takeover_whose_start_check_reads_the_arm_late_is_not_refused(fast, monkeypatch):
    """The physics runs on 40 ms (simulated) between the gate's clock and its reading of the joints (a CPU-starved
    batch): the arm is that much further along the same curve, which is no jump (before: 422 'the trajectory starts
    0.12 rad from where waist is', seen over HTTP under CPU hogs)."""
    station, cell = fast
    at_rest(station, [-1.5, 0.0, 0.0, 0.0, 0.0])
    station.move_joints([1.5, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.8)  # the waist turns at ~3 rad/s
    joints_rad = station.gate.joints_rad

    def late_reading():
        cell.step(0.04)
        return joints_rad()

    monkeypatch.setattr(station.gate, "joints_rad", late_reading)
    cell.start_joint_recording()
    station.move_joints([-1.0, 0.0, 0.0, 0.0, 0.0])  # reverse
    monkeypatch.undo()
    _assert_continuous(_figures(cell, 2.5))
    assert not station.arm.is_moving() and abs(station.joints_rad()[0] + 1.0) < 0.01


def test_moves_and_jogs_take_over_one_another_continuously(fast):
    station, cell = fast
    at_rest(station, [0.0, -0.3, 0.3, 0.5, 0.0])
    cell.start_joint_recording()
    station.move_joints([1.2, 0.2, 0.1, 0.9, 1.0])
    cell.step(0.3)
    station.jog([-0.8, 0.0, 0.0, 0.0, 0.5], source="pad")  # a jog takes over the move
    for _ in range(4):
        cell.step(0.05)
        assert station.heartbeat(source="pad")
    station.move_to([0.0, 0.25, 0.15])  # a pose move takes over the jog
    cell.step(0.2)
    station.home()
    _assert_continuous(_figures(cell, 3.0))
    assert np.allclose(station.joints_rad(), 0.0, atol=0.02)


def test_a_job_started_while_the_arm_moves_brakes_it_first(fast):
    station, cell = fast
    at_rest(station, [-2.5, 0.0, 0.0, 0.0, 0.0])
    program = station.store.save_program("after a move", [Waypoint((0.0, -0.3, 0.3, 0.9, 0.0), "release"),
                                                          Waypoint((0.4, 0.0, 0.3, 1.0, 0.0), "release")])
    station.move_joints([2.5, 0.0, 0.0, 0.0, 0.0])
    cell.step(0.6)
    cell.start_joint_recording()
    cell.step(0.05)
    started_s = cell.sim_time_s
    job = skills.repeat(station, program.id, cycles=1)
    assert job.wait(120) and job.state == "succeeded", job.message
    trace = cell.stop_joint_recording()
    slow = np.all(np.abs(np.diff(trace["reference_rad"], axis=0)) < 2e-5, axis=1) & (trace["time_s"][1:] > started_s)
    braked = int(np.flatnonzero(slow)[0]) + 1  # the command first stands still: the brake's end, before the job moves
    figures = motion_figures({key: value[:braked] for key, value in trace.items()})
    _assert_continuous(figures)
    assert abs(trace["reference_rad"][braked, 0]) < 1.0  # stopped short of the move's goal: braked, not waited


def test_a_jobs_trajectory_that_does_not_continue_the_motion_is_refused(fast):
    station, cell = fast
    at_rest(station, [-1.2, 0.0, 0.0, 0.0, 0.0])
    refused = []

    def line(q, delta, duration_s):  # constant velocity from q, 100 samples per second
        s = np.linspace(0.0, 1.0, int(duration_s * 100) + 1)
        return JointTrajectory(s * duration_s, q + s[:, None] * np.asarray(delta, float))

    def job(ctx):
        station.start_trajectory(ctx, line(station.joints_rad(), [0.2, 0, 0, 0, 0], 2.0))  # a slow start: 0.1 rad/s
        station.wait_in_job(ctx, lambda: station.clock_s() > 1.0 + start[0], 5.0)
        try:  # planned from rest where the arm is measured, while it moves at 0.1 rad/s
            station.start_trajectory(ctx, line(station.joints_rad(), [-0.3, 0, 0, 0, 0], 3.0))
        except ArmMoving as error:
            refused.append(str(error))
        station.wait_in_job(ctx, lambda: not station.arm.is_moving(), 5.0)

    start = [station.clock_s()]
    handle = station.start_job("grab", "test", job)
    assert handle.wait(30) and handle.state == "succeeded", handle.message
    assert refused and "does not continue it" in refused[0], refused
    assert abs(station.joints_rad()[0] - (-1.0)) < 0.01  # the first trajectory ran to its end


def test_a_replacement_the_trajectory_library_cannot_plan_is_refused_and_the_motion_goes_on(fast):
    """Issue 18 item 2: a ruckig failure while re-planning (the real 'ValueError: -101 is not a valid Result' of the
    CI run here: limits far below the motion in progress) is a ValueError naming the library; the running
    trajectory is not touched."""
    from armlab.motion.blend import Limits, plan_run

    station, cell = fast
    at_rest(station, [-1.0, 0.0, 0.0, 0.0, 0.0])
    outcome = {}

    def job(ctx):
        station.move_in_job(ctx, [-1.0, 0.0, 0.0, 0.0, 0.0])  # at rest, then a move the job replaces
        q = station.joints_rad()
        s = np.linspace(0.0, 1.0, 201)
        station.start_trajectory(ctx, JointTrajectory(s * 2.0, q + s[:, None] * np.array([0.6, 0, 0, 0, 0])))
        station.wait_in_job(ctx, lambda: station.clock_s() > outcome.setdefault("t0", station.clock_s()) + 0.5, 5.0)
        tiny = Limits(np.full(5, 1e-2), np.full(5, 1e-5), np.full(5, 1e-5))
        try:
            station.replace_trajectory(ctx, lambda h: plan_run(np.vstack([h.position_rad, q]), tiny, start_velocity=h.velocity_rad_s).trajectory)
        except ValueError as error:
            outcome["refused"] = str(error)
        station.wait_in_job(ctx, lambda: not station.arm.is_moving(), 10.0)

    handle = station.start_job("grab", "replan", job)
    assert handle.wait(30) and handle.state == "succeeded", handle.message
    assert "trajectory library (ruckig) found no trajectory: ValueError: -101" in outcome.get("refused", ""), outcome
    assert abs(station.joints_rad()[0] - (-0.4)) < 0.01  # the running trajectory went on to its end


def test_a_burst_of_moves_plans_only_the_newest(fast, monkeypatch):
    """Moves that come in while another is being planned (42 clients at once, a script's burst) wait their turn,
    and those a newer one replaces before their turn are refused unplanned (409): the planner's CPU went to ~40
    plans, each at once replaced, and starved status and the physics (bench/estop.py)."""
    station, _ = fast
    at_rest(station, [0.0, 0.0, 0.0, 0.0, 0.0])
    held, planned, entered, outcomes = threading.Event(), [], [], {}
    send_replacing, plan_move, plan_move_from = station.gate.send_replacing, station.manual.plan_move, station.manual.plan_move_from

    def counting(original):
        def plan(*args, **kwargs):
            planned.append(args)
            if len(planned) == 1:
                assert held.wait(60)  # the first plan takes its time while the others come in
            return original(*args, **kwargs)
        return plan

    def entering(*args, **kwargs):
        entered.append(threading.current_thread().name)
        return send_replacing(*args, **kwargs)

    monkeypatch.setattr(station.manual, "plan_move", counting(plan_move))
    monkeypatch.setattr(station.manual, "plan_move_from", counting(plan_move_from))
    monkeypatch.setattr(station.gate, "send_replacing", entering)

    def move(waist_rad: float) -> None:
        try:
            station.move_joints([waist_rad, 0.0, 0.0, 0.0, 0.0])
            outcomes[threading.current_thread().name] = "sent"
        except ArmMoving as error:
            outcomes[threading.current_thread().name] = str(error)

    goals = {f"move {i}": 0.1 * i for i in range(1, 9)}
    threads = {name: threading.Thread(target=move, args=(waist,), name=name, daemon=True) for name, waist in goals.items()}
    threads["move 1"].start()
    _until(lambda: len(planned) == 1)
    for name in list(goals)[1:]:
        threads[name].start()
    _until(lambda: len(entered) == len(goals))
    held.set()
    for thread in threads.values():
        thread.join(60)
    monkeypatch.undo()
    newest = entered[-1]
    assert outcomes["move 1"] == "sent" and outcomes[newest] == "sent"
    assert len(planned) == 2, f"{len(planned)} plans for a burst of {len(goals)} moves"
    assert all("newer" in outcome for name, outcome in outcomes.items() if name not in ("move 1", newest)), outcomes
    station.wait_motion(10.0)
    assert abs(station.joints_rad()[0] - goals[newest]) < 0.01


def _until(predicate, polls: int = 60_000) -> None:
    """Poll predicate() (another thread makes it true), yielding the GIL between polls; AssertionError if it never holds."""
    for _ in range(polls):
        if predicate():
            return
        threading.Event().wait(0.001)
    raise AssertionError("the other threads never got there")
