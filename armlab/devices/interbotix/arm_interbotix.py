"""InterbotixArm: the Arm interface on a real Interbotix X-Series arm (ROS 2 xs_sdk node).

Thin by design (no hardware in CI): trajectories are streamed as position goals at stream_rate_hz
through InterbotixArmXSInterface.publish_positions, each goal executed by the motors' time-based
profile of profile_time_s; joint states come from the core's /joint_states. Limits are the ones the
xs_sdk reports for the 'arm' group. Checks (connected, shape, finite, limits) happen before anything moves.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from armlab.config import read_config_file, resolve_config_path
from armlab.devices.arm import Arm, JointState, JointTrajectory
from armlab.devices.frame_buffer import ReaderThread
from armlab.devices.interbotix.configuration_interbotix import InterbotixArmConfig
from armlab.devices.interbotix.connection import InterbotixConnection
from armlab.errors import DeviceAlreadyConnectedError, DeviceNotConnectedError


class InterbotixArm(Arm):
    """Joint-space position control of an Interbotix arm; share `connection` with InterbotixGripper."""

    def __init__(self, config: InterbotixArmConfig, connection: InterbotixConnection | None = None) -> None:
        self.config = config
        self.connection = connection or InterbotixConnection(config.connection)
        arm_file = read_config_file(resolve_config_path(config.arm_config, "arms"))
        self.joint_names = tuple(arm_file["joint_names"])
        self._bot = None
        self._lower_rad = self._upper_rad = None
        self._lock = threading.Lock()
        self._trajectory: JointTrajectory | None = None
        self._trajectory_start_s = 0.0
        self._done = threading.Event()
        self._done.set()
        self._streamer: ReaderThread | None = None

    def __str__(self) -> str:
        return f"InterbotixArm({self.config.connection.robot_name or self.config.connection.robot_model})"

    @property
    def is_connected(self) -> bool:
        return self._bot is not None

    def connect(self) -> None:
        if self.is_connected:
            raise DeviceAlreadyConnectedError(f"{self}: already connected; call close() before connecting again")
        try:
            bot = self.connection.open()
        except (ImportError, ConnectionError) as error:  # say which device could not connect
            raise type(error)(f"{self}: {error}") from error
        try:
            info = bot.arm.group_info
            names = tuple(info.joint_names)
            if names != self.joint_names:
                raise ConnectionError(f"{self}: the robot's arm joints are {names}, the arm config expects {self.joint_names}")
            self._lower_rad = np.asarray(info.joint_lower_limits, float)
            self._upper_rad = np.asarray(info.joint_upper_limits, float)
            bot.core.robot_torque_enable("group", self.config.connection.group_name, True)
            self._bot = bot
            self._streamer = ReaderThread(f"{self}-streamer", self._stream_step)
            self._streamer.start()
        except BaseException:
            self._bot = None
            self.connection.release()
            raise

    def close(self) -> None:
        """Stop streaming (the arm holds its last goal) and release the connection. Safe twice."""
        if self._bot is None:
            return
        self._clear_trajectory()
        if self._streamer is not None:
            self._streamer.stop()
            self._streamer = None
        self._bot = None
        self.connection.release()

    def _require_connected(self):
        if self._bot is None:
            raise DeviceNotConnectedError(f"{self}: not connected: call connect() first")
        return self._bot

    def read_joint_state(self) -> JointState:
        bot = self._require_connected()
        with bot.core.js_mutex:
            states = bot.core.joint_states
            indices = [bot.core.js_index_map[name] for name in self.joint_names]
            position = np.array([states.position[i] for i in indices], float)
            velocity = np.array([states.velocity[i] for i in indices], float) if states.velocity else np.zeros(len(indices))
        return JointState(position_rad=position, velocity_rad_s=velocity, timestamp_s=time.time())

    def command_trajectory(self, trajectory: JointTrajectory, wait: bool = False, start_time_s: float | None = None) -> float:
        """See Arm.command_trajectory: streamed from start_time_s on time.monotonic() (None: now)."""
        bot = self._require_connected()
        positions = trajectory.positions_rad
        if positions.shape[1] != len(self.joint_names):
            raise ValueError(f"{self}: trajectory has {positions.shape[1]} joints, the arm has {len(self.joint_names)}")
        outside = np.argwhere((positions < self._lower_rad) | (positions > self._upper_rad))
        if outside.size:
            sample, joint = (int(v) for v in outside[0])
            raise ValueError(
                f"{self}: {self.joint_names[joint]} = {positions[sample, joint]:.4f} rad at t = "
                f"{trajectory.times_s[sample]:.3f} s is outside [{self._lower_rad[joint]:.4f}, {self._upper_rad[joint]:.4f}]"
            )
        bot.arm.set_trajectory_time(self.config.profile_time_s, self.config.profile_accel_time_s)
        with self._lock:
            self._trajectory = trajectory
            self._trajectory_start_s = time.monotonic() if start_time_s is None else float(start_time_s)
            started_s = self._trajectory_start_s
            self._done.clear()
        if wait:
            self._done.wait()
        return started_s

    def _clear_trajectory(self) -> None:
        with self._lock:
            self._trajectory = None
            self._done.set()

    def _stream_step(self, stop) -> bool:
        """Send the current trajectory sample, then sleep to the next tick; end a finished trajectory."""
        period_s = 1.0 / self.config.stream_rate_hz
        tick_s = time.monotonic()
        with self._lock:
            trajectory, start_s = self._trajectory, self._trajectory_start_s
        if trajectory is not None:
            elapsed_s = tick_s - start_s
            self._bot.arm.publish_positions(trajectory.sample(elapsed_s).tolist(), blocking=False)
            if elapsed_s >= trajectory.duration_s:
                with self._lock:
                    if self._trajectory is trajectory:
                        self._trajectory = None
                        self._done.set()
        stop.wait(max(0.0, period_s - (time.monotonic() - tick_s)))
        return True

    def is_moving(self) -> bool:
        self._require_connected()
        return not self._done.is_set()

    def stop(self) -> None:
        """Drop the trajectory and hold the measured position."""
        bot = self._require_connected()
        self._clear_trajectory()
        bot.arm.publish_positions(self.read_joint_state().position_rad.tolist(), blocking=False)

    def set_torque(self, enabled: bool) -> None:
        bot = self._require_connected()
        if not enabled:
            self._clear_trajectory()
        bot.core.robot_torque_enable("group", self.config.connection.group_name, bool(enabled))
