"""Gripper path recording: samples in simulated time taken inside the physics stepping (fast mode
records while a blocking move runs), equal to gripper_point_m() at those times, bounded in memory."""

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.devices.sim.path import PathRecorder
from sim_helpers import move, topdown_ik


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(seed=2, color_noise=False, depth_noise=False)) as sim:
        yield sim


def test_a_blocking_move_in_fast_mode_is_recorded_at_the_requested_rate(cell):
    cell.start_path_recording(period_s=0.05)
    start_s = cell.sim_time_s
    move(cell, topdown_ik((0.15, 0.25, 0.05)), duration_s=1.5)  # blocks: the physics steps inside
    move(cell, topdown_ik((-0.15, 0.20, 0.10)), duration_s=1.5)
    path = cell.gripper_path()
    assert path.shape[1] == 4 and path[0, 0] == pytest.approx(start_s)
    steps = np.diff(path[:, 0])
    assert np.all(steps > 0) and steps.max() <= 0.1 + 1e-6, "at least 10 Hz of simulated time"
    assert np.median(steps) == pytest.approx(0.05, abs=0.0025)
    assert path[-1, 0] >= cell.sim_time_s - 0.05
    assert np.linalg.norm(path[-1, 1:] - cell.gripper_point_m()) < 0.001
    travelled = np.linalg.norm(np.diff(path[:, 1:], axis=0), axis=1).sum()
    assert travelled > 0.3, "the path follows the arm"


def test_samples_equal_the_gripper_point_at_their_simulated_times(cell):
    q0 = cell.arm.read_joint_state().position_rad
    q1 = topdown_ik((0.20, 0.15, 0.04))
    times = np.linspace(0.0, 1.2, 121)
    cell.arm.command_trajectory(JointTrajectory(times, q0 + np.outer(times / 1.2, q1 - q0)))
    cell.start_path_recording(period_s=0.02)
    seen = {}
    for _ in range(70):  # read the gripper point ourselves every 0.02 s of simulated time
        cell.step(0.02)
        seen[round(cell.sim_time_s, 6)] = cell.gripper_point_m()
    path = cell.gripper_path()
    matched = 0
    for t, *point in path[1:]:
        if round(t, 6) in seen:
            assert np.linalg.norm(np.array(point) - seen[round(t, 6)]) < 0.001
            matched += 1
    assert matched >= 60
    assert np.ptp(path[:, 1:], axis=0).max() > 0.05, "the arm moved while recording"


def test_stop_returns_the_samples_and_recording_ends(cell):
    cell.start_path_recording(period_s=0.1)
    cell.step(0.5)
    path = cell.stop_path_recording()
    assert len(path) == 6
    cell.step(0.5)
    assert cell.gripper_path().shape == (0, 4)


def test_bad_period_is_refused_and_keeps_the_current_recording(cell):
    cell.start_path_recording(period_s=0.1)
    cell.step(0.2)
    for bad in (0.0, -1.0, float("nan"), "fast"):
        with pytest.raises(ValueError, match="period_s"):
            cell.start_path_recording(period_s=bad)
    assert len(cell.gripper_path()) == 3


def test_memory_is_bounded_and_keeps_the_newest_samples():
    recorder = PathRecorder(period_s=0.01, max_duration_s=1.0)
    for k in range(5000):
        t = k * 0.01
        if recorder.due(t):
            recorder.record(t, (t, 0.0, 0.0))
    samples = recorder.samples()
    assert len(samples) == recorder.capacity == 101
    assert recorder.dropped == 5000 - 101
    assert samples[-1, 0] == pytest.approx(49.99) and np.all(np.diff(samples[:, 0]) > 0)
    assert np.array_equal(samples[:, 0], samples[:, 1])
