"""Issue 21, a pendant's global speed override: one percentage for every motion the station plans. Ground truth is
the simulation's clock and its joint recording (every control tick), on a fast synchronous station: a manual move
and a job's motion at 50 % take twice the simulated time they take at 100 %; a change while a motion runs keeps
the command continuous and within the acceleration limits; bad values change nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.errors import InvalidInput
from armlab.kinematics import load_arm
from armlab.motion.measure import motion_figures

ARM = load_arm("rx200")
FAR_Q = np.array([0.8, 0.3, 0.2, 0.4, 0.5])
OTHER_Q = np.array([-0.6, -0.2, 0.4, -0.3, -0.5])


def _moving_span_s(trace: dict) -> float:
    """Simulated seconds from the first to the last tick at which the commanded reference moves."""
    reference = np.asarray(trace["reference_rad"])
    moving = np.flatnonzero(np.abs(np.diff(reference, axis=0)).max(axis=1) > 1e-7)
    return float(trace["time_s"][moving[-1] + 1] - trace["time_s"][moving[0]])


def _timed(cell, motion) -> tuple[float, dict]:
    cell.start_joint_recording()
    motion()
    trace = cell.stop_joint_recording()
    return _moving_span_s(trace), trace


def _at_sleep(station):
    station.set_speed(100)
    station.sleep(wait=True)


def _at_home(station):
    station.set_speed(100)
    station.home(wait=True)


@pytest.fixture(autouse=True)
def full_speed_after(fast):
    yield
    fast[0].set_speed(100)


def test_a_manual_move_at_50_percent_takes_twice_the_simulated_time(fast):
    station, cell = fast
    spans = {}
    for speed in (100, 50):
        _at_home(station)
        station.set_speed(speed)
        spans[speed], trace = _timed(cell, lambda: station.move_joints(FAR_Q, wait=True))
        assert np.allclose(trace["reference_rad"][-1], FAR_Q, atol=1e-6)
    assert spans[50] / spans[100] == pytest.approx(2.0, abs=0.05), spans
    assert station.status()["speed_percent"] == 50.0


def test_a_job_motion_honours_the_override(fast):
    """run_trajectory, the gate's path for every job's motion (grabs, drops, the tasks)."""
    station, cell = fast
    spans = {}
    for speed in (100, 50):
        _at_home(station)
        station.set_speed(speed)

        def job_motion():
            job = station.start_job("grab", "a job's move", lambda ctx: station.move_in_job(ctx, OTHER_Q))
            assert job.wait(120) and job.state == "succeeded", job.message

        spans[speed], _ = _timed(cell, job_motion)
    assert spans[50] / spans[100] == pytest.approx(2.0, abs=0.05), spans


@pytest.mark.parametrize("first, then", [(100, 30), (30, 100)])
def test_a_change_during_a_move_retimes_it_continuously_within_the_limits(fast, first, then):
    station, cell = fast
    _at_sleep(station)
    station.set_speed(first)
    _, alone = _timed(cell, lambda: station.move_joints(FAR_Q, wait=True))
    _at_sleep(station)
    station.set_speed(first)
    cell.start_joint_recording()
    station.move_joints(FAR_Q)
    start = cell.sim_time_s
    # a third of the way: cruising, not braking at the limit (physics runs in the wait)
    station.gate.wait_until(lambda: cell.sim_time_s >= start + _moving_span_s(alone) / 3, 10.0)
    station.set_speed(then)
    station.wait_motion(60.0)
    trace = cell.stop_joint_recording()
    span, span_alone = _moving_span_s(trace), _moving_span_s(alone)
    assert (span > 1.3 * span_alone) if then < first else (span < 0.8 * span_alone), (span, span_alone, [e["message"] for e in station.events.since(0)[-3:]])
    assert np.allclose(trace["reference_rad"][-1], FAR_Q, atol=1e-6)
    figures = motion_figures(trace)
    command, _ = figures.ratio(ARM.accel_limit_rad_s2)
    assert command <= 1.01, f"the command accelerates at {command:.2f}x the limit"
    velocity = np.abs(np.asarray(trace["reference_velocity_rad_s"]))
    assert np.all(velocity <= np.asarray(ARM.velocity_limit_rad_s) * 1.01)
    assert float(figures.step_rad.max()) < 1e-3, "the command jumps"
    assert not any("applies from the next motion" in e["message"] for e in station.events.since(0)[-3:])


@pytest.mark.parametrize("bad", [math.nan, 0, 1000, "fast", None, math.inf, 9.9])
def test_bad_values_are_refused_and_change_nothing(fast, bad):
    station, _ = fast
    station.set_speed(70)
    with pytest.raises(InvalidInput):
        station.set_speed(bad)
    assert station.speed_percent == 70.0


def _moving_time_s(trace: dict) -> float:
    """Simulated seconds during which the commanded reference moves (the gripper's waits left out)."""
    reference = np.asarray(trace["reference_rad"])
    moving = np.abs(np.diff(reference, axis=0)).max(axis=1) > 1e-7
    return float(np.sum(np.diff(np.asarray(trace["time_s"]))[moving]))


def test_a_grab_job_at_50_percent_moves_twice_as_long(fast):
    """A real job (click-grab of a detected block): its arm motion takes twice the simulated time at 50 %."""
    from armlab import skills
    from armlab.scene import Scene

    station, cell = fast
    block = {"id": "cube", "type": "block", "color": "red", "size": "large", "position_m": [0.1, 0.22, 0.019], "yaw_rad": 0.2}
    _at_home(station)
    job = skills.calibrate(station)
    assert job.wait(60) and job.state == "succeeded", job.message
    moving = {}
    for speed in (100, 50):
        _at_home(station)
        cell.set_scene(Scene.from_dict({"objects": [block]}))
        station.fresh_perception()
        station.set_speed(speed)
        cell.start_joint_recording()
        job = skills.grab(station, position_m=[0.1, 0.22, 0.038])
        assert job.wait(120) and job.state == "succeeded", job.message
        moving[speed] = _moving_time_s(cell.stop_joint_recording())
        assert cell.truth()["gripper"]["holding_id"] == "cube"
        station.set_speed(100)
        station.gripper_command("release")
        station.set_held_block(None)
    assert moving[50] / moving[100] == pytest.approx(2.0, abs=0.08), moving
