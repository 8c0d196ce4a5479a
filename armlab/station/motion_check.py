"""The full safety check of a trajectory before the gate sends it: limits, the table, the workspace box, the per-step
jump, the gripper's parts against the board and the arm against itself. Owned by the motion gate (motion.py); pure
reads of the arm model, the motion config, the end effector and what the gripper holds, so it needs no lock."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import InvalidInput
from armlab.motion import check_trajectory
from armlab.motion.clearance import self_collision
from armlab.motion.end_effector import EndEffector
from armlab.motion.safety import UnsafeTrajectory
from armlab.station.body_check import check_parts_above_board, palm_corners_m
from armlab.station.checks import checked_joints
from armlab.station.held import HeldBlock


class MotionCheck:
    """check_motion, check_pose, check_poses and the boxes they keep above the board.

    model: the (calibrated) ArmModel; motion_config(): armlab.motion's MotionConfig (read late: loaded on first use);
    end_effector(): the station's end effector; held_block(): what the gripper holds (its edge_m), None: nothing."""

    def __init__(self, model: Any, motion_config: Callable[[], Any], end_effector: Callable[[], EndEffector],
                 held_block: Callable[[], HeldBlock | None]) -> None:
        self.model = model
        self._motion_config, self._end_effector, self._held_block = motion_config, end_effector, held_block

    def checked_joints(self, q_rad) -> np.ndarray:
        """A finite joint vector inside the limits (InvalidInput naming the joint otherwise)."""
        return checked_joints(self.model, q_rad)

    def check_motion(self, trajectory: JointTrajectory) -> None:
        """The full safety check of a trajectory (UnsafeTrajectory says why): joint, velocity and
        acceleration limits, the table, the workspace box, the per-step jump. No lock needed (pure)."""
        config = self._motion_config()
        # The table itself (no clearance): planners keep their own board_clearance_m; the straight joint-space
        # move from the sleep pose home passes the gripper point within 1 mm of the board.
        check_trajectory(self.model, trajectory, workspace_m=config.workspace_m, max_step_rad=config.max_step_rad)
        self.check_body(trajectory)

    def check_pose(self, q_rad) -> np.ndarray:
        """The arm standing at q_rad passes the trajectory check (limits, the table, the workspace box, the fingers
        against the board, the arm against itself): returns the joints; ValueError / UnsafeTrajectory say why."""
        q = self.checked_joints(q_rad)
        self.check_motion(JointTrajectory(np.array([0.0, 0.01]), np.vstack([q, q])))
        return q

    def check_poses(self, poses_rad) -> None:
        """check_pose of every pose, the error naming the 1-based waypoint (programs, drafts)."""
        for index, q in enumerate(poses_rad, start=1):
            try:
                self.check_pose(q)
            except UnsafeTrajectory as error:
                raise UnsafeTrajectory(f"waypoint {index}: {error}") from None
            except InvalidInput as error:
                raise InvalidInput(f"waypoint {index}: {error}") from None

    def check_body(self, trajectory: JointTrajectory) -> None:
        """UnsafeTrajectory (with the reason and when) if the fingers (a box around them, or the suction cup's
        body) go into the board, or the gripper end of the arm (gripper point, finger tips, the held block) into
        the arm's own base or upper arm, at any sample (armlab.motion.clearance). No lock needed (pure)."""
        config, positions, times = self._motion_config(), trajectory.positions_rad, trajectory.times_s
        parts = {"fingers": self.finger_box().corners_m()}
        if (palm := self.palm_corners_m()) is not None:
            parts["palm"] = palm
        check_parts_above_board(self.model, positions, times, parts)
        held = self._held_block()
        held_edge_m = float(held.edge_m) if held is not None and held.edge_m else None
        hit = self_collision(self.model, positions, base_radius_m=config.base_radius_m, reach_m=config.self_clearance_m,
                             held_edge_m=held_edge_m)
        if hit is not None:
            sample, part, what = hit
            raise UnsafeTrajectory(f"{what} at t = {times[sample]:.3f} s: the arm would hit itself", part=part,
                                   at_q_rad=positions[sample])

    def palm_corners_m(self) -> np.ndarray | None:
        """(8, 3) corners of a finger gripper's palm in the gripper frame; None for a suction cup."""
        return palm_corners_m(self.model.config.name) if self._end_effector().has_palm else None

    def finger_box(self):
        """The box the gripper occupies beyond the wrist (armlab.motion.gripper_step.FingerBox): the open fingers
        from config, or the suction cup's body."""
        return self._end_effector().body_box(self._motion_config(), self.model.config)
