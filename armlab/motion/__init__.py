"""Motion planning: time-parameterised joint trajectories, vertical Cartesian segments, pick/place
plans and the safety check every plan passes before it reaches the arm. Pure functions, no devices.

Kinematics come from an arm model (armlab.kinematics.load_arm).
"""

from armlab.motion.cartesian import plan_vertical_segment
from armlab.motion.errors import DiscontinuousPath
from armlab.motion.pick_place import (
    GripperStep,
    Step,
    TrajectoryStep,
    plan_move_to_pose,
    plan_pick,
    plan_place,
)
from armlab.motion.safety import UnsafeTrajectory, check_trajectory
from armlab.motion.trajectory import MoveTiming, plan_joint_move, plan_joint_move_timed
from armlab.motion_config import MotionConfig, load_motion_config

__all__ = [
    "DiscontinuousPath",
    "GripperStep",
    "MotionConfig",
    "MoveTiming",
    "Step",
    "TrajectoryStep",
    "UnsafeTrajectory",
    "check_trajectory",
    "load_motion_config",
    "plan_joint_move",
    "plan_joint_move_timed",
    "plan_move_to_pose",
    "plan_pick",
    "plan_place",
    "plan_vertical_segment",
]
