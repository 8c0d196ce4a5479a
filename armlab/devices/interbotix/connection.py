"""InterbotixConnection: one InterbotixManipulatorXS shared by the arm and gripper adapters.

interbotix_xs_modules (ROS 2) is imported only in open(), and a missing install is an
InterbotixNotInstalledError (an ImportError) telling what to install. Reference-counted so the
arm and the gripper can share one ROS node; the last close() shuts it down.
"""

from __future__ import annotations

import threading

from armlab.devices.interbotix.configuration_interbotix import InterbotixConnectionConfig


class InterbotixNotInstalledError(ImportError):
    """interbotix_xs_modules (ROS 2) is not importable; the message says what to install."""


INSTALL_HINT = (
    "the Interbotix backend needs ROS 2 and the Interbotix X-Series packages: install ROS 2 (Humble or "
    "later), then the interbotix_ros_manipulators workspace (https://docs.trossenrobotics.com/"
    "interbotix_xsarms_docs/ros_interface/ros2/software_setup.html), source its setup.bash, and launch "
    "`ros2 launch interbotix_xsarm_control xsarm_control.launch.py robot_model:=rx200` before connecting"
)


def import_manipulator_class():
    """InterbotixManipulatorXS from interbotix_xs_modules, or InterbotixNotInstalledError."""
    try:
        from interbotix_xs_modules.xs_robot.arm import InterbotixManipulatorXS
    except ImportError as error:
        raise InterbotixNotInstalledError(f"cannot import interbotix_xs_modules ({error}); {INSTALL_HINT}") from error
    return InterbotixManipulatorXS


class InterbotixConnection:
    """A shared handle on InterbotixManipulatorXS; `bot` is valid between open() and the last close()."""

    def __init__(self, config: InterbotixConnectionConfig) -> None:
        self.config = config
        self._lock = threading.Lock()
        self._users = 0
        self.bot = None

    def __str__(self) -> str:
        return f"InterbotixConnection({self.config.robot_name or self.config.robot_model})"

    def open(self):
        """Create the manipulator on first use (talks to a running xs_sdk node); return it."""
        with self._lock:
            if self.bot is None:
                manipulator_class = import_manipulator_class()
                config = self.config
                try:
                    self.bot = manipulator_class(
                        robot_model=config.robot_model,
                        group_name=config.group_name,
                        gripper_name=config.gripper_name,
                        robot_name=config.robot_name,
                        node_name=config.node_name,
                    )
                except Exception as error:
                    raise ConnectionError(f"{self}: could not reach the xs_sdk node: {error}") from error
            self._users += 1
            return self.bot

    def release(self) -> None:
        """Drop one user; shut the ROS node down when none remain. Safe to call extra times."""
        with self._lock:
            if self._users == 0:
                return
            self._users -= 1
            if self._users == 0 and self.bot is not None:
                bot, self.bot = self.bot, None
                bot.shutdown()
