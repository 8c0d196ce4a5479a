"""The workcell's device contracts and clocks: connect/close errors, joint limits refuse and move
nothing, stop halts within a control period, fast mode is deterministic, set_scene swaps objects at
run time, and real-time mode paces physics to the wall clock with frames at the camera rate."""

import threading
import time

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError
from armlab.scene import generate_scene
from sim_helpers import move


@pytest.fixture(scope="module")
def cell():
    with SimWorkcell(SimWorkcellConfig(seed=1)) as sim:
        yield sim


def linear(q0, q1, duration_s):
    times = np.linspace(0.0, duration_s, int(duration_s * 100) + 1)
    return JointTrajectory(times, q0 + np.outer(times / duration_s, np.asarray(q1) - q0))


def test_devices_refuse_use_before_connect_and_double_connect():
    sim = SimWorkcell(SimWorkcellConfig(seed=0))
    try:
        with pytest.raises(DeviceNotConnectedError):
            sim.arm.read_joint_state()
        with pytest.raises(DeviceNotConnectedError):
            sim.gripper.grasp()
        with pytest.raises(DeviceNotConnectedError):
            sim.camera.read()
        sim.start()
        for device in (sim.arm, sim.gripper, sim.camera):
            assert device.is_connected
            with pytest.raises(DeviceAlreadyConnectedError):
                device.connect()
    finally:
        sim.close()
        sim.close()  # safe twice
    assert not sim.arm.is_connected


@pytest.mark.parametrize(
    "bad_target,message",
    [
        ([0.0, 2.5, 0.0, 0.0, 0.0], "shoulder"),  # 143 deg > 113 deg
        ([0.0, 0.0, -1.95, 0.0, 0.0], "elbow"),  # -112 deg < -108 deg
        ([0.0, 0.0, 0.0, 0.0], r"\(N, 5\)"),
    ],
)
def test_commands_outside_limits_or_of_wrong_shape_raise_and_move_nothing(cell, bad_target, message):
    before = cell.arm.read_joint_state().position_rad
    ctrl_before = cell._data.ctrl.copy()
    times = np.array([0.0, 1.0])
    positions = np.array([before[: len(bad_target)], bad_target])
    with pytest.raises(ValueError, match=message):
        cell.arm.command_trajectory(JointTrajectory(times, positions))
    assert not cell.arm.is_moving()
    assert np.array_equal(cell._data.ctrl, ctrl_before)
    cell.step(0.2)
    assert np.abs(cell.arm.read_joint_state().position_rad - before).max() < 1e-3


def test_nan_trajectories_cannot_even_be_built():
    with pytest.raises(ValueError, match="finite"):
        JointTrajectory(np.array([0.0, 1.0]), np.array([[0.0] * 5, [np.nan] + [0.0] * 4]))


def test_trajectory_is_tracked_and_wait_returns_when_done(cell):
    q0 = cell.arm.read_joint_state().position_rad
    target = np.array([0.3, -0.2, 0.4, 1.0, 0.5])
    start = cell.sim_time_s
    cell.arm.command_trajectory(linear(q0, target, 1.5), wait=True)
    assert not cell.arm.is_moving()
    assert 1.5 <= cell.sim_time_s - start <= 1.5 + 0.6
    assert np.abs(cell.arm.read_joint_state().position_rad - target).max() < 0.003


def test_stop_halts_within_one_control_period(cell):
    q0 = cell.arm.read_joint_state().position_rad
    cell.arm.command_trajectory(linear(q0, q0 + [1.0, 0.3, 0.3, 0.3, 1.0], 2.0))
    cell.step(0.5)
    assert np.abs(cell.arm.read_joint_state().velocity_rad_s).max() > 0.2
    cell.arm.stop()
    assert not cell.arm.is_moving()
    held = cell.arm.read_joint_state().position_rad
    assert np.allclose(cell._data.ctrl[cell._pos_act], held)  # the servo reference is the stop pose now
    cell.step(0.5)
    # The servos brake from ~0.75 rad/s: overshoot stays small and the arm holds still afterwards.
    after = cell.arm.read_joint_state()
    assert np.abs(after.position_rad - held).max() < 0.03
    assert np.abs(after.velocity_rad_s).max() < 0.01


def test_torque_off_goes_limp_and_refuses_motion(cell):
    move(cell, [0.0, 0.0, 0.0, 0.0, 0.0])
    cell.arm.set_torque(False)
    with pytest.raises(ValueError, match="torque"):
        cell.arm.command_trajectory(linear(cell.arm.read_joint_state().position_rad, np.zeros(5), 1.0))
    cell.step(1.0)
    assert cell.arm.read_joint_state().position_rad[1] > 0.3, "the shoulder falls forward under gravity"
    cell.arm.set_torque(True)
    held = cell.arm.read_joint_state().position_rad
    cell.step(0.5)
    assert np.abs(cell.arm.read_joint_state().position_rad - held).max() < 0.02
    move(cell, [0.0, -1.0, 1.0, 0.5, 0.0])


def run_sequence(seed):
    with SimWorkcell(SimWorkcellConfig(seed=seed), scene=generate_scene("pick_sort", 3, seed=seed)) as sim:
        sim.step(0.3)
        q0 = sim.arm.read_joint_state().position_rad
        sim.arm.command_trajectory(linear(q0, [0.5, 0.3, 0.2, 1.0, 0.2], 1.0), wait=True)
        sim.gripper.grasp()
        frame = sim.camera.read()
        return sim.truth(), frame


def test_fast_mode_is_deterministic_for_a_seed():
    truth_a, frame_a = run_sequence(5)
    truth_b, frame_b = run_sequence(5)
    truth_c, _ = run_sequence(6)
    assert truth_a == truth_b
    assert np.array_equal(frame_a.color_bgr, frame_b.color_bgr)
    assert np.array_equal(frame_a.depth_mm, frame_b.depth_mm)
    assert truth_a["objects"] != truth_c["objects"]
    assert truth_a["camera"]["T_world_camera"] != truth_c["camera"]["T_world_camera"]


def test_camera_read_advances_to_the_next_frame_time(cell):
    first = cell.camera.read()
    t1 = cell.sim_time_s
    second = cell.camera.async_read()
    assert second.sequence == first.sequence + 1
    assert cell.sim_time_s - t1 == pytest.approx(1.0 / 30.0, abs=0.003)
    latest = cell.camera.read_latest(max_age_ms=10_000)
    assert latest.sequence == second.sequence
    times = []
    for _ in range(8):  # frame times land on the 30 fps clock (to the 2 ms physics step), always advancing
        cell.camera.read()
        times.append(cell.sim_time_s)
    gaps = np.diff(times)
    assert gaps.min() > 0.02 and gaps.max() < 1.0 / 30.0 + 0.0021
    assert np.mean(gaps) == pytest.approx(1.0 / 30.0, abs=0.001)


def test_set_scene_replaces_objects_and_keeps_the_arm_pose(cell):
    move(cell, [0.2, -0.5, 0.6, 0.8, 0.0])
    q_before = cell.arm.read_joint_state().position_rad
    cell.set_scene(generate_scene("line_up", 1, seed=2))
    assert sorted(o["color"] for o in cell.truth()["objects"]) == sorted(["red", "orange", "yellow", "green", "blue", "violet"])
    cell.set_scene(generate_scene("pick_sort", 1, seed=2).to_dict())  # the dict form works too
    truth = cell.truth()
    assert len(truth["objects"]) == 3
    cell.step(0.5)
    assert np.abs(cell.arm.read_joint_state().position_rad - q_before).max() < 0.003
    for obj, start in zip(cell.truth()["objects"], generate_scene("pick_sort", 1, seed=2).objects):
        assert np.allclose(obj["position_m"], start.position_m, atol=0.001)
    assert cell.render().color_bgr.shape == (720, 1280, 3)  # the renderer follows the new model
    with pytest.raises(ValueError):
        cell.set_scene([1, 2, 3])
    cell.arm.command_trajectory(JointTrajectory(np.array([0.0, 0.3]), np.array([q_before, q_before])))
    moved = cell.truth()["objects"][0]["id"]
    body = cell._object_bodies[moved]
    cell._data.qpos[cell.model.jnt_qposadr[cell.model.body_jntadr[body]]] += 0.05  # nudge one block
    cell.step(0.3)
    assert cell.truth()["objects"][0]["position_m"][0] != pytest.approx(truth["objects"][0]["position_m"][0], abs=0.01)
    cell.reset_scene()
    assert np.allclose(cell.truth()["objects"][0]["position_m"], truth["objects"][0]["position_m"], atol=1e-6)
    assert len(cell.truth()["objects"]) == 3


def test_truth_has_the_documented_structure(cell):
    truth = cell.truth()
    assert set(truth["camera"]) >= {"K", "width", "height", "T_world_camera"}
    assert np.array(truth["camera"]["T_world_camera"]).shape == (4, 4)
    for obj in truth["objects"]:
        assert set(obj) >= {"id", "type", "color", "size", "position_m", "yaw_rad", "quat_wxyz"}
    assert set(truth["gripper"]) >= {"left_contacts", "right_contacts", "holding_id", "width_m"}


def test_a_time_scale_runs_the_real_time_physics_ahead_of_the_wall_clock_at_its_pace():
    """time_scale 3: three simulated seconds a wall second (the tests' whole-job runs), never more."""
    with SimWorkcell(SimWorkcellConfig(realtime=True, seed=0, camera_fps=5.0, time_scale=3.0)) as sim:
        wall0, sim0 = time.monotonic(), sim.sim_time_s
        _sim_wait(sim, 1.5, timeout_s=30.0)
        factor = (sim.sim_time_s - sim0) / (time.monotonic() - wall0)
        assert 1.1 < factor < 3.1, factor  # ahead of the wall clock, never past its pace; loose below for a busy CI
    with pytest.raises(ValueError):
        SimWorkcellConfig(realtime=True, time_scale=0.0)


def test_realtime_mode_paces_physics_to_the_wall_clock_and_streams_frames():
    config = SimWorkcellConfig(realtime=True, seed=0, camera_fps=15.0)
    threads_before = set(threading.enumerate())
    with SimWorkcell(config, scene=generate_scene("pick_sort", 1, seed=0)) as sim:
        with pytest.raises(RuntimeError):
            sim.step(0.1)
        first = sim.camera.async_read(timeout_ms=3000)
        wall0, sim0 = time.monotonic(), sim.sim_time_s
        q0 = sim.arm.read_joint_state().position_rad
        sim.arm.command_trajectory(linear(q0, [0.3, -0.8, 0.8, 0.6, 0.0], 1.0))
        frames = [sim.camera.async_read(timeout_ms=3000) for _ in range(5)]
        assert [f.sequence for f in frames] == sorted({f.sequence for f in frames})
        assert frames[0].sequence > first.sequence
        assert sim.arm.wait_until_done(timeout_s=5.0)
        factor = (sim.sim_time_s - sim0) / (time.monotonic() - wall0)
        assert 0.3 < factor < 1.1, factor  # never faster than the wall clock; lower bound loose for a busy CI
        q1 = sim.arm.read_joint_state().position_rad
        sim.arm.command_trajectory(linear(q1, q1 + [0.8, 0.0, 0.0, 0.0, 0.0], 1.0))
        _sim_wait(sim, 0.3)
        sim.arm.stop()
        assert not sim.arm.is_moving()
        stopped = sim.arm.read_joint_state().position_rad
        _sim_wait(sim, 0.3)
        assert abs(sim.arm.read_joint_state().position_rad[0] - stopped[0]) < 0.05
        assert sim.camera.read_latest(max_age_ms=1000).color_bgr.shape == (720, 1280, 3)
    assert not [t for t in set(threading.enumerate()) - threads_before if t.name.startswith("sim-")]


def _sim_wait(sim, duration_s: float, timeout_s: float = 10.0) -> None:
    """Until duration_s of simulated time has passed (a condition on the sim clock, not a fixed sleep)."""
    start, deadline = sim.sim_time_s, time.monotonic() + timeout_s
    while sim.sim_time_s < start + duration_s:
        assert time.monotonic() < deadline, "the simulation did not advance"
        time.sleep(0.005)
