"""Every trajectory the gate sends, from any source (manual moves, jogs, jobs' run_trajectory), passes the
full safety check before anything moves: here with a workspace box narrowed to |x| <= 0.3 m, a trajectory
that would not start where the arm is, and one that jumps between samples."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.motion.safety import UnsafeTrajectory
from armlab.motion.trajectory import plan_joint_move
from armlab.motion_config import MotionConfig
from armlab.station import State
from station_helpers import back_to_idle, still_for

FACING_X = np.array([-math.pi / 2, 0.0, 0.0, 0.0, 0.0])  # gripper point at x = 0.41 m: outside the box


@pytest.fixture(scope="module")
def station(cell, db_path):
    from armlab.kinematics import load_arm
    from armlab.station import Station, StationConfig

    station = Station(
        cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), sim=cell,
        config=StationConfig(database_path=str(db_path)),
        motion_config=MotionConfig(workspace_min_m=(-0.30, -0.40, 0.0), workspace_max_m=(0.30, 0.60, 0.70)),
    )
    station.start()
    yield station
    station.close()


@pytest.fixture()
def idle(station):
    back_to_idle(station)
    station.move_joints(station.model.home_rad, moving_time_s=0.8, wait=True)
    yield station
    back_to_idle(station)


def test_a_manual_move_out_of_the_box_is_refused_and_nothing_moves(cell, idle):
    station = idle
    with pytest.raises(UnsafeTrajectory, match="workspace box"):
        station.move_joints(FACING_X)
    assert still_for(cell, station, 0.3)
    with pytest.raises(UnsafeTrajectory, match="workspace box"):
        station.move_joints([-0.8, 0, 0, 0, 0], moving_time_s=0.8, wait=True)  # gripper point at x = 0.293 m
        station.jog([-0.8, 0, 0, 0, 0])  # its plan (ramp up, 0.2 s, ramp down: ~0.16 rad) sweeps past x = 0.3 m
    assert still_for(cell, station, 0.3)


@pytest.mark.parametrize("flaw", ["out of the box", "not from here", "jumps"])
def test_a_jobs_unsafe_trajectory_is_refused_before_anything_moves(cell, idle, flaw):
    station = idle
    home = np.asarray(station.model.home_rad, dtype=float)
    if flaw == "out of the box":
        trajectory = plan_joint_move(home, FACING_X, station.model)
    elif flaw == "not from here":
        trajectory = plan_joint_move(home + np.array([0.3, 0, 0, 0, 0]), home + np.array([0.5, 0, 0, 0, 0]), station.model)
    else:
        times = np.array([0.0, 1.0, 2.0])
        trajectory = JointTrajectory(times, np.array([home, home + [0.3, 0, 0, 0, 0], home + [0.3, 0, 0, 0, 0]]))
    job = station.start_job("auto", f"unsafe: {flaw}", lambda ctx: station.run_trajectory(ctx, trajectory))
    assert job.wait(10)
    assert job.state == "failed" and "UnsafeTrajectory" in job.message, job.message
    assert station.state is State.IDLE  # a refused plan is not a device failure
    assert still_for(cell, station, 0.3)
