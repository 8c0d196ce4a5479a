"""The job planners on the UR3 suction station (skills.manipulate, skills.side_grasp): a pick comes
straight down the cup's axis onto the block's top face centre and the grasp depth of fingers does not
apply; side grasps and side places, which need fingers, are refused with a clear reason before anything
moves. FK of the planned joints (the workcell's kinematics model) is the truth. Fast-mode simulation."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import Unreachable
from armlab.motion import GripperStep, TrajectoryStep
from armlab.skills import side_grasp
from armlab.skills.manipulate import plan_pick, plan_place, plan_side_place
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.workcell import load_workcell_arm
from armlab.workcell.loading import load_workcell_motion_config

WORKCELL = "ur3_suction"
TOP_M = np.array([0.10, 0.30, 0.038])
DOWN = np.array([0.0, 0.0, -1.0])


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    with SimWorkcell(SimWorkcellConfig(workcell=WORKCELL, realtime=False, seed=1)) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_workcell_arm(WORKCELL),
                          config=StationConfig(workcell=WORKCELL), store=Store(tmp_path_factory.mktemp("s") / "s.sqlite3"),
                          sim=cell, synchronous=True, motion_config=load_workcell_motion_config(WORKCELL))
        station.start()
        yield station
        station.close()


def _moves(steps) -> dict:
    return {step.name: step.trajectory for step in steps if isinstance(step, TrajectoryStep)}


def test_a_job_pick_comes_straight_down_the_cup_axis_onto_the_top_face(station):
    steps = plan_pick(station, TOP_M, 0.3, 0.038, boxes=[])
    assert [s.action for s in steps if isinstance(s, GripperStep)] == ["release", "grasp"]
    for name in ("descend to grasp", "lift"):
        T = station.model.fk(_moves(steps)[name].positions_rad)
        tilt_deg = np.degrees(np.arccos(np.clip(T[:, :3, 0] @ DOWN, -1.0, 1.0))).max()
        assert tilt_deg < 0.1, f"{name}: the cup axis is {tilt_deg:.2f}° off vertical"
        assert np.abs(T[:, :2, 3] - TOP_M[:2]).max() < 0.0005
    lowest_m = station.model.fk(_moves(steps)["descend to grasp"].positions_rad[-1])[2, 3]
    assert TOP_M[2] - 0.005 < lowest_m <= TOP_M[2], f"the cup stops at {lowest_m * 1000:.1f} mm, not on the top face"


def test_a_job_place_releases_the_held_block_just_above_the_surface(station):
    steps = plan_place(station, [-0.15, 0.30, 0.0], 0.0, 0.038, boxes=[])
    T = station.model.fk(_moves(steps)["descend to place"].positions_rad)
    assert np.degrees(np.arccos(np.clip(T[:, :3, 0] @ DOWN, -1.0, 1.0))).max() < 0.1
    bottom_m = T[-1, 2, 3] + station.motion_config.suction_press_m - 0.038  # the cup holds the block's top face
    assert 0.0 < bottom_m <= 0.01


def test_side_grasps_and_side_places_need_fingers(station):
    with pytest.raises(Unreachable, match="needs fingers"):
        side_grasp.plan_side_pick_place(station, TOP_M, [-0.15, 0.30, 0.0], 0.038, [], [], [0.0])
    with pytest.raises(Unreachable, match="needs fingers"):
        plan_side_place(station, [-0.15, 0.30, 0.1], 0.038, [])
