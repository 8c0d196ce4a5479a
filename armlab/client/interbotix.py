"""Interbotix-style names over the station, so a script written for the real RX200 runs against it.

    from armlab.client import InterbotixManipulatorXS
    bot = InterbotixManipulatorXS("rx200", "arm", "gripper", url="http://127.0.0.1:8000", token="...")
    bot.arm.go_to_home_pose(); bot.arm.set_ee_pose_components(x=0.25, z=0.15, pitch=1.2)
    bot.gripper.grasp(); bot.arm.go_to_sleep_pose()

Coordinates follow Interbotix: set_ee_pose_components takes x, y, z in the arm's BASE frame (x
forward, y left); the station works in the world frame (world_x = -base_y, world_y = base_x).

Only for Interbotix arms: the facade asks the station which arm it runs (GET /api/arm) and refuses,
with NotInterbotixArm, a station whose arm is not made by Interbotix or is not the robot_model asked
for (a UR3 has six joints, another base frame and a suction cup: use StationClient there).
"""

from __future__ import annotations

from collections.abc import Sequence

from armlab.client.station_client import StationClient, StationError


def base_to_world(x: float, y: float, z: float) -> list[float]:
    """Interbotix base-frame point → station world frame (DESIGN §3)."""
    return [-float(y), float(x), float(z)]


class InterbotixArmFacade:
    """bot.arm: Interbotix's InterbotixArmXSInterface names."""

    def __init__(self, client: StationClient, moving_time: float = 2.0, accel_time: float = 0.3) -> None:
        self._client = client
        self.moving_time = moving_time
        self.accel_time = accel_time

    def set_trajectory_time(self, moving_time: float | None = None, accel_time: float | None = None) -> None:
        if moving_time is not None:
            self.moving_time = float(moving_time)
        if accel_time is not None:
            self.accel_time = float(accel_time)

    def set_joint_positions(
        self, joint_positions: Sequence[float], moving_time: float | None = None, accel_time: float | None = None, blocking: bool = True
    ) -> bool:
        """Move to joint positions (rad). accel_time is accepted for compatibility; the planner's ramps apply."""
        self._client.move_joints(joint_positions, moving_time_s=moving_time or self.moving_time, wait=blocking)
        return True

    def set_single_joint_position(self, joint_name: str, position: float, moving_time=None, accel_time=None, blocking=True) -> bool:
        status = self._client.status()
        q = list(status["joints_rad"])
        q[status["joint_names"].index(joint_name)] = float(position)
        return self.set_joint_positions(q, moving_time, accel_time, blocking)

    def set_ee_pose_components(
        self, x: float = 0.0, y: float = 0.0, z: float = 0.0, roll: float = 0.0, pitch: float = 0.0, yaw: float | None = None,
        moving_time: float | None = None, accel_time: float | None = None, blocking: bool = True,
    ) -> tuple[list[float], bool]:
        """Gripper point at (x, y, z) in the base frame with the given pitch (Interbotix: +pitch = down).

        roll is not settable on a 5-dof arm (must be 0); yaw follows from x, y (accepted, ignored). Returns (joint goal, success) like Interbotix;
        an unreachable pose returns (current joints, False) and nothing moves.
        """
        if roll != 0.0:
            raise ValueError("the RX200 cannot set roll independently: use roll=0")

        try:
            status = self._client.move_to(
                base_to_world(x, y, z), pitch_rad=float(pitch), yaw_rad=None, moving_time_s=moving_time or self.moving_time, wait=blocking
            )
        except StationError as error:
            if error.code in ("unreachable", "unsafe"):
                return list(self._client.status()["joints_rad"]), False
            raise
        return list(status["joints_rad"]), True

    def go_to_home_pose(self, moving_time: float | None = None, accel_time: float | None = None, blocking: bool = True) -> None:
        self._client.home(wait=blocking, moving_time_s=moving_time or self.moving_time)

    def go_to_sleep_pose(self, moving_time: float | None = None, accel_time: float | None = None, blocking: bool = True) -> None:
        self._client.sleep(wait=blocking, moving_time_s=moving_time or self.moving_time)

    def get_joint_commands(self) -> list[float]:
        return list(self._client.status()["joints_rad"])

    def get_ee_pose(self) -> dict:
        return self._client.status()["gripper_pose"]


class InterbotixGripperFacade:
    """bot.gripper: grasp() / release()."""

    def __init__(self, client: StationClient) -> None:
        self._client = client

    def grasp(self, delay: float = 0.0) -> None:
        self._client.grasp()

    def release(self, delay: float = 0.0) -> None:
        self._client.release()


class NotInterbotixArm(RuntimeError):
    """The station's arm is not the Interbotix arm the facade was asked for."""


def check_interbotix_arm(arm: dict, robot_model: str) -> None:
    """NotInterbotixArm unless the station's arm (GET /api/arm) is made by Interbotix and is robot_model."""
    name, vendor = arm.get("name"), arm.get("vendor")
    what = f"the station runs the {name} ({vendor or 'vendor not given'}, {len(arm.get('joint_names', []))} joints, {arm.get('gripper_type')})"
    if vendor != "interbotix":
        raise NotInterbotixArm(
            f"{what}: InterbotixManipulatorXS drives only Interbotix arms; use armlab.client.StationClient for this arm"
        )
    if name != robot_model:
        raise NotInterbotixArm(f"{what}, not the {robot_model!r} asked for: pass robot_model={name!r}")


class InterbotixManipulatorXS:
    """bot = InterbotixManipulatorXS(robot_model="rx200", group_name="arm", gripper_name="gripper", url=..., token=...)."""

    def __init__(
        self,
        robot_model: str = "rx200",
        group_name: str = "arm",
        gripper_name: str = "gripper",
        moving_time: float = 2.0,
        accel_time: float = 0.3,
        url: str = "http://127.0.0.1:8000",
        token: str | None = None,
        **_ignored,
    ) -> None:
        self.robot_model = robot_model
        self.client = StationClient(url, token)
        try:
            check_interbotix_arm(self.client.arm(), robot_model)
        except BaseException:
            self.client.close()
            raise
        self.arm = InterbotixArmFacade(self.client, moving_time, accel_time)
        self.gripper = InterbotixGripperFacade(self.client)

    def shutdown(self) -> None:
        self.client.close()
