"""A pendant user lets go of one hold and presses another at once (x+ then y−, a joint then z+): the new jog starts
while the previous one still brakes. It is accepted (it was refused, "waist accelerates at 35.5 rad/s²", before the
running motion was brought to rest first) and the arm stays within its acceleration limit; the new line then runs.
Fast synchronous simulation, measured on its clock at every control tick."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion.blend import arm_limits
from armlab.motion.measure import motion_figures

ARM = load_arm("rx200")
START_M = [0.0, 0.25, 0.12]


def _jog(station, kind, sign=1):
    if kind in ("x", "y", "z"):
        station.jog_cartesian(kind, sign * station.motion_config.jog_max_speed_m_s, source="pad")
    else:
        station.jog([sign * 0.5, 0, 0, 0, 0], source="pad")


@pytest.mark.parametrize("first, second", [("x", "y"), ("joint", "z"), ("y", "joint")])
def test_a_new_hold_while_the_last_one_brakes_is_accepted_within_the_limits(fast, first, second):
    station, cell = fast
    station.move_joints(station.solve_pose(START_M, pitch_rad=math.pi / 2, yaw_rad=0.0), wait=True)
    station.wait_motion(5.0)
    cell.start_joint_recording()
    _jog(station, first)
    for _ in range(6):
        cell.step(0.05)
        assert station.heartbeat(source="pad")
    assert station.stop_jog(source="pad")
    cell.step(0.02)  # still braking
    assert station.arm.is_moving()
    point = cell.gripper_point_m()
    _jog(station, second, -1)
    for _ in range(6):
        cell.step(0.05)
        assert station.heartbeat(source="pad"), "the second hold ended while heartbeats arrived"
    cell.step(1.0)
    trace = cell.stop_joint_recording()
    assert motion_figures(trace).ratio(arm_limits(ARM).accel_rad_s2)[0] <= 1.05  # the command within the limit
    moved = cell.gripper_point_m() - point
    if second in ("x", "y", "z"):
        axis = "xyz".index(second)
        assert moved[axis] < -0.02, f"the {second}− jog moved the gripper {moved * 1000} mm"
        others = [i for i in range(3) if i != axis]
        assert np.abs(moved[others]).max() < 0.02  # the braking of the first jog's last few mm at most
