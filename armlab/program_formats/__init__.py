"""Taught programs in other people's files: ROS 2 bags of joint states (rosbag2.py, with `rosbags`) and the
ROB 550 course's joint text files (jointdata.py), both read as recorded samples (samples.py) that become a
program's waypoints, thinned or as a trajectory, after the joint limit check. Programs and repeat traces are
written as ROS 2 bags too. Pure: no station, no database (armlab.skills.program_files puts them in the store).
"""

from armlab.program_formats.jointdata import parse_jointdata
from armlab.program_formats.rosbag2 import (
    STORAGES,
    joint_states_bytes,
    read_joint_states,
    read_joint_states_bytes,
    write_joint_states,
    write_trace,
)
from armlab.program_formats.samples import MODES, Converted, ImportOptions, JointSamples, to_program

__all__ = [
    "MODES",
    "STORAGES",
    "Converted",
    "ImportOptions",
    "JointSamples",
    "joint_states_bytes",
    "parse_jointdata",
    "read_joint_states",
    "read_joint_states_bytes",
    "to_program",
    "write_joint_states",
    "write_trace",
]
