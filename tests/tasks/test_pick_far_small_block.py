"""A small block far out, reached only at a pitch short of top-down: the pick's descent keeps the open fingers'
box and the palm above the board (the gate's own body check), its grasp raised by what they dipped (at most
MAX_GRASP_RAISE_M). Before, the gate refused such picks ("the fingers would go 2.8 mm into the board": the real arm,
calibrated, on pick_sort L3 seed 3; the nominal arm from 0.38 m out). Plan level, no simulation."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from armlab.kinematics import load_arm
from armlab.motion import TrajectoryStep
from armlab.motion.end_effector import end_effector
from armlab.motion_config import load_motion_config
from armlab.skills import manipulate
from armlab.skills.manipulate import MAX_GRASP_RAISE_M, plan_pick
from armlab.station.body_check import check_parts_above_board, palm_corners_m

ARM = load_arm("rx200")
CONFIG = load_motion_config()
FINGERS = end_effector("fingers")
SMALL_M = 0.025


@pytest.fixture
def station(monkeypatch):
    monkeypatch.setattr(manipulate, "station_end_effector", lambda _station: FINGERS)
    return SimpleNamespace(model=ARM, motion_config=CONFIG, start_position=lambda: np.asarray(ARM.sleep_rad, float),
                           finger_box=lambda: FINGERS.body_box(CONFIG, ARM.config), palm_corners_m=lambda: palm_corners_m(ARM.config.name))


@pytest.mark.parametrize("reach_m", [0.36, 0.40, 0.43, 0.45])
def test_far_small_block_pick_passes_the_body_check(station, reach_m):
    top = np.array([0.0, reach_m, SMALL_M])
    steps = plan_pick(station, top, 0.0, SMALL_M, [])
    parts = {"fingers": station.finger_box().corners_m(), "palm": station.palm_corners_m()}
    for step in steps:
        if isinstance(step, TrajectoryStep):
            check_parts_above_board(ARM, step.trajectory.positions_rad, step.trajectory.times_s, parts)
    grasp_z = [s for s in steps if isinstance(s, TrajectoryStep) and s.name == "descend to grasp"][0].trajectory
    grasp_z_m = ARM.fk(grasp_z.positions_rad[-1])[2, 3]
    nominal_z_m = SMALL_M - CONFIG.grasp_depth_for(SMALL_M)
    assert nominal_z_m - 1e-4 <= grasp_z_m <= nominal_z_m + MAX_GRASP_RAISE_M + 1e-4  # raised only as needed, bounded
