"""The repeat job on a synchronous fast-mode station (issue 9): absolute deadlines (every cycle exactly the
planned cycle time on the simulated clock), pause holds the arm, step goes one waypoint, resume finishes,
a speed change takes effect mid-run, and refused programs move nothing."""

from __future__ import annotations

import numpy as np
import pytest

from armlab import skills
from armlab.errors import CommandRefused
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.repeat_plan import plan_cycle
from armlab.store import NotFound, Waypoint
from station_helpers import live

PROGRAM = [
    Waypoint((0.0, -0.3, 0.3, 0.9, 0.0), "release"),
    Waypoint((0.45, 0.05, 0.35, 1.0, 0.0), "release"),
    Waypoint((0.9, 0.2, 0.1, 1.1, 0.3), "release"),
    Waypoint((0.9, 0.2, 0.1, 1.1, 0.3), "grasp"),
    Waypoint((0.5, -0.2, -0.1, 1.2, 0.3), "grasp", 0.3),
    Waypoint((-0.2, -0.4, 0.2, 0.9, 0.0), "release"),
]
STILL_TOL_RAD = 5e-3


@pytest.fixture(scope="module")
def fast(tmp_path_factory):
    from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
    from armlab.kinematics import load_arm
    from armlab.station import Station, StationConfig

    cell = SimWorkcell(SimWorkcellConfig(realtime=False, seed=0))
    cell.start()
    db = tmp_path_factory.mktemp("repeat") / "station.sqlite3"
    station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(database_path=str(db)),
                      sim=cell, backend="sim", synchronous=True)
    station.start()
    yield station, cell
    station.close()
    cell.close()


def _extra(job) -> dict:
    return job.to_dict().get("extra", {}).get("repeat", {})


def test_cycles_are_paced_by_absolute_deadlines(fast):
    station, _ = fast
    program = station.store.save_program("paced", PROGRAM)
    plan = plan_cycle(station, program, 80.0)
    job = skills.repeat(station, program.id, cycles=20, speed_percent=80)
    assert job.wait(300) and job.state == "succeeded", job.message
    starts = np.asarray(job.result["cycle_starts_s"])
    durations = np.diff(starts)
    assert len(starts) == 20
    assert np.all(np.abs(durations - plan.cycle_s) < 1e-6), durations  # each cycle the planned time, on the sim clock
    assert abs((starts[-1] - starts[0]) - 19 * plan.cycle_s) < 1e-3  # no drift over 20 cycles
    assert plan.blended_runs >= 1
    assert np.allclose(station.joints_rad(), 0.0, atol=0.02)  # home at the end


def test_pause_holds_step_goes_one_waypoint_resume_finishes(fast):
    station, cell = fast
    program = station.store.save_program("pausable", PROGRAM)
    job = skills.repeat(station, program.id, cycles=2, speed_percent=50)
    live.wait_for(lambda: _extra(job).get("phase") == "cycle" or job.done, 60, 0.001)
    station.pause_job()
    live.wait_for(lambda: _extra(job).get("phase") == "paused" and not station.arm.is_moving(), 60, 0.005)
    held, at = station.joints_rad(), cell.sim_time_s
    live.wait_for(lambda: cell.sim_time_s > at + 0.5, 60, 0.005)  # 0.5 s of simulated time paused
    assert np.max(np.abs(station.joints_rad() - held)) < STILL_TOL_RAD
    assert job.state == "running" and station.state.value == "repeat"
    waypoint = _extra(job)["waypoint"]
    station.step_job()
    live.wait_for(lambda: _extra(job)["waypoint"] != waypoint and _extra(job)["paused"] and not station.arm.is_moving(), 60, 0.005)
    assert _extra(job)["waypoint"] in (waypoint + 1, 1)  # the next one (or the first after the last)
    stepped = station.joints_rad()
    target = np.asarray(PROGRAM[_extra(job)["waypoint"] - 1].joints_rad)
    assert np.max(np.abs(stepped - target)) < 0.02  # stopped on that waypoint
    station.resume_job()
    assert job.wait(300) and job.state == "succeeded", job.message
    assert job.result["cycles_done"] == 2


def test_a_speed_change_during_the_run_applies_to_the_rest(fast):
    station, _ = fast
    program = station.store.save_program("speed", PROGRAM)
    slow = plan_cycle(station, program, 30.0)
    job = skills.repeat(station, program.id, cycles=6, speed_percent=100)
    live.wait_for(lambda: _extra(job).get("phase") == "cycle" or job.done, 60, 0.001)
    station.set_job_speed(30)
    assert job.wait(300) and job.state == "succeeded", job.message
    assert job.result["speed_percent"] == 30
    durations = np.diff(job.result["cycle_starts_s"])
    assert np.all(np.abs(durations[-2:] - slow.cycle_s) < 1e-6), (durations, slow.cycle_s)  # the later cycles at 30 %
    with pytest.raises(CommandRefused):
        station.set_job_speed(50)  # no repeat running any more
    with pytest.raises(ValueError):
        skills.repeat(station, program.id, cycles=1, speed_percent=120)


def test_refused_programs_move_nothing(fast):
    station, _ = fast
    before = station.joints_rad()
    outside = station.store.save_program("outside", [PROGRAM[0], Waypoint((0.0, 2.5, 0.0, 0.0, 0.0), "release")])
    with pytest.raises(ValueError, match="waypoint 2: joint 'shoulder'"):
        skills.repeat(station, outside.id)
    below = station.store.save_program("below", [PROGRAM[0], Waypoint((0.0, 1.9, 1.6, 0.0, 0.0), "release")])
    with pytest.raises(UnsafeTrajectory, match="waypoint 2"):
        skills.repeat(station, below.id)
    with pytest.raises(NotFound):
        skills.repeat(station, 10_000)
    good = station.store.save_program("good", PROGRAM)
    for cycles in (0, -1, True, 1.5):
        with pytest.raises(ValueError):
            skills.repeat(station, good.id, cycles=cycles)
    station.teach.start(discard_draft=True)
    with pytest.raises(CommandRefused):
        skills.repeat(station, good.id)
    station.estop()
    station.reset()
    assert station.state.value == "idle" and not station.arm.is_moving()
    assert np.max(np.abs(station.joints_rad() - before)) < STILL_TOL_RAD
