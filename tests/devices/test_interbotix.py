"""The Interbotix adapters against a stand-in for interbotix_xs_modules (ROS 2 cannot run in CI).

The stand-in mimics the few calls the adapters make (group_info, joint_states under js_mutex,
set_trajectory_time, publish_positions, robot_torque_enable, gripper_controller) and tracks
commands perfectly, so these tests check the adapters' own logic: streaming, validation, stop,
shared connection, gripper width and holding.
"""

from __future__ import annotations

import sys
import threading
import time
import types

import numpy as np
import pytest

from armlab.devices.factory import make_devices
from armlab.errors import DeviceAlreadyConnectedError
from armlab.kinematics import load_arm
from armlab.motion import plan_joint_move

ARM_JOINTS = ["waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate"]
MODEL = load_arm("rx200")


class _Core:
    def __init__(self, finger_m: float) -> None:
        self.js_mutex = threading.Lock()
        names = [*ARM_JOINTS, "gripper", "left_finger", "right_finger"]
        self.js_index_map = {name: index for index, name in enumerate(names)}
        self.joint_states = types.SimpleNamespace(
            name=names, position=[0.0] * 6 + [finger_m, -finger_m], velocity=[0.0] * 8
        )
        self.torque_calls: list[tuple[str, str, bool]] = []

    def robot_torque_enable(self, cmd_type: str, name: str, enable: bool) -> None:
        self.torque_calls.append((cmd_type, name, enable))


class _ArmGroup:
    def __init__(self, core: _Core, joint_names) -> None:
        self.core = core
        self.group_info = types.SimpleNamespace(
            joint_names=list(joint_names),
            joint_lower_limits=MODEL.lower_rad.tolist(),
            joint_upper_limits=MODEL.upper_rad.tolist(),
        )
        self.profile = None
        self.published: list[list[float]] = []

    def set_trajectory_time(self, moving_time=None, accel_time=None) -> None:
        self.profile = (moving_time, accel_time)

    def publish_positions(self, positions, moving_time=None, accel_time=None, blocking=True) -> None:
        assert blocking is False  # the streamer must never block
        self.published.append(list(positions))
        with self.core.js_mutex:  # perfect tracking
            self.core.joint_states.position[:5] = list(positions)


class _Gripper:
    gripper_value = 250.0
    left_finger_index = 6

    def __init__(self, core: _Core, block_width_m: float | None) -> None:
        self.core = core
        self.block_width_m = block_width_m
        self.efforts: list[float] = []
        self.pressure = None

    def set_pressure(self, pressure: float) -> None:
        self.pressure = pressure

    def gripper_controller(self, effort: float, delay: float) -> None:
        self.efforts.append(effort)
        if effort < 0:  # closing: stops on the block's faces (pads 6 mm) or fully closed at 15 mm
            finger = 0.015 if self.block_width_m is None else self.block_width_m / 2 + 0.006
        elif effort > 0:
            finger = 0.037
        else:
            return
        with self.core.js_mutex:
            self.core.joint_states.position[6] = finger


def _install_fake_interbotix(monkeypatch, joint_names=ARM_JOINTS, block_width_m=None) -> list:
    """Put a stand-in interbotix_xs_modules.xs_robot.arm into sys.modules; returns the created bots."""
    created: list = []

    class InterbotixManipulatorXS:
        def __init__(self, robot_model, group_name="arm", gripper_name="gripper", robot_name=None, node_name="x"):
            self.core = _Core(finger_m=0.037)
            self.arm = _ArmGroup(self.core, joint_names)
            self.gripper = _Gripper(self.core, block_width_m)
            self.shut_down = False
            self.args = (robot_model, group_name, gripper_name, robot_name, node_name)
            created.append(self)

        def shutdown(self) -> None:
            self.shut_down = True

    package = types.ModuleType("interbotix_xs_modules")
    robot = types.ModuleType("interbotix_xs_modules.xs_robot")
    arm_module = types.ModuleType("interbotix_xs_modules.xs_robot.arm")
    arm_module.InterbotixManipulatorXS = InterbotixManipulatorXS
    monkeypatch.setitem(sys.modules, "interbotix_xs_modules", package)
    monkeypatch.setitem(sys.modules, "interbotix_xs_modules.xs_robot", robot)
    monkeypatch.setitem(sys.modules, "interbotix_xs_modules.xs_robot.arm", arm_module)
    return created


def _devices():
    return make_devices("interbotix_arm", "interbotix_gripper", {"type": "opencv", "source": 0})


def test_arm_and_gripper_share_one_node_and_the_last_close_shuts_it_down(monkeypatch):
    created = _install_fake_interbotix(monkeypatch)
    devices = _devices()
    devices.arm.connect()
    devices.gripper.connect()
    assert len(created) == 1 and created[0].args[:2] == ("rx200", "arm")
    bot = created[0]
    assert bot.core.torque_calls == [("group", "arm", True)] and bot.gripper.pressure == 0.5
    with pytest.raises(DeviceAlreadyConnectedError, match=r"^InterbotixArm\(rx200\)"):
        devices.arm.connect()
    devices.arm.close()
    assert not bot.shut_down  # the gripper still uses it
    devices.gripper.close()
    devices.gripper.close()  # safe twice
    assert bot.shut_down


def test_trajectory_is_streamed_to_the_goal_and_wait_blocks_until_done(monkeypatch):
    created = _install_fake_interbotix(monkeypatch)
    arm = _devices().arm
    arm.connect()
    try:
        goal = np.array([0.4, -0.2, 0.3, 0.5, -0.3])
        trajectory = plan_joint_move(np.zeros(5), goal, MODEL, moving_time_s=0.3)
        arm.command_trajectory(trajectory, wait=True)
        assert not arm.is_moving()
        bot = created[0]
        assert bot.arm.profile == (0.1, 0.0)  # the configured per-goal profile
        published = np.array(bot.arm.published)
        np.testing.assert_allclose(published[-1], goal)  # ends exactly at the goal
        # every streamed goal lies on the planned straight joint-space path, in order
        progress = published[:, 0] / goal[0]
        np.testing.assert_allclose(published, progress[:, None] * goal[None, :], atol=1e-9)
        assert np.all(np.diff(progress) >= -1e-12) and len(published) >= 3
        np.testing.assert_allclose(arm.read_joint_state().position_rad, goal)
    finally:
        arm.close()


def test_out_of_limits_or_wrong_dof_moves_nothing(monkeypatch):
    created = _install_fake_interbotix(monkeypatch)
    arm = _devices().arm
    arm.connect()
    try:
        from armlab.devices.arm import JointTrajectory

        beyond = JointTrajectory(np.array([0.0, 0.01]), np.array([[0.0] * 5, [0.0, 2.5, 0.0, 0.0, 0.0]]))
        with pytest.raises(ValueError, match=r"^InterbotixArm\(rx200\): shoulder = 2\.5000 rad at t = 0\.010 s"):
            arm.command_trajectory(beyond)
        with pytest.raises(ValueError, match="trajectory has 4 joints"):
            arm.command_trajectory(JointTrajectory(np.array([0.0]), np.zeros((1, 4))))
        time.sleep(0.03)
        assert created[0].arm.published == [] and not arm.is_moving()
    finally:
        arm.close()


def test_stop_drops_the_trajectory_and_holds_the_measured_position(monkeypatch):
    created = _install_fake_interbotix(monkeypatch)
    arm = _devices().arm
    arm.connect()
    try:
        trajectory = plan_joint_move(np.zeros(5), np.array([1.0, 0.0, 0.0, 0.0, 0.0]), MODEL, moving_time_s=5.0)
        arm.command_trajectory(trajectory)
        deadline = time.monotonic() + 2.0
        while len(created[0].arm.published) < 3 and time.monotonic() < deadline:
            time.sleep(0.005)
        assert arm.is_moving()
        arm.stop()
        assert not arm.is_moving()
        held = created[0].arm.published[-1]
        assert 0.0 <= held[0] < 1.0  # stopped part-way, not at the goal
        np.testing.assert_allclose(arm.read_joint_state().position_rad, held)
        count = len(created[0].arm.published)
        time.sleep(0.05)
        assert len(created[0].arm.published) == count  # nothing streamed after stop
    finally:
        arm.close()


def test_joint_name_mismatch_fails_connect_and_releases_the_node(monkeypatch):
    created = _install_fake_interbotix(monkeypatch, joint_names=["waist", "shoulder", "elbow", "wrist_angle"])
    arm = _devices().arm
    with pytest.raises(ConnectionError, match=r"^InterbotixArm\(rx200\): the robot's arm joints are"):
        arm.connect()
    assert not arm.is_connected and created[0].shut_down


@pytest.mark.parametrize("block_width_m, holding", [(0.025, True), (None, False)])
def test_gripper_width_and_holding(monkeypatch, block_width_m, holding):
    created = _install_fake_interbotix(monkeypatch, block_width_m=block_width_m)
    gripper = _devices().gripper
    gripper.connect()
    try:
        state = gripper.read_state()
        assert state.width_m == pytest.approx(0.062) and not state.holding  # fully open: 2*37 - 2*6 mm
        gripper.grasp()
        assert created[0].gripper.efforts[-1] < 0  # negative effort closes
        state = gripper.read_state()
        assert state.command == "grasp" and state.holding is holding
        assert state.width_m == pytest.approx(block_width_m if holding else 0.018)
        gripper.release()
        assert created[0].gripper.efforts[-1] > 0 and gripper.read_state().width_m == pytest.approx(0.062)
    finally:
        gripper.close()
