"""Click-to-world never uses the robot's depth (issue 9, item 1), on a calibrated fast-mode simulation:
with the arm placed on the camera ray of a board spot (so the live depth at that pixel is the arm's),
the clicked point is the board or the surface last seen there (ground truth within a few mm), a drop
there lands the block where the pixel points, and a grab that closes on nothing or a drop with an
empty gripper ends as a failed job saying why."""

from __future__ import annotations

import math

import numpy as np
import pytest

from armlab import skills
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig
from armlab.kinematics import load_arm
from armlab.scene import Scene
from armlab.skills.perceive import pixel_to_world
from armlab.station import State
from armlab.station.config import StationConfig
from armlab.station.core import Station
from armlab.store import Store
from armlab.vision.geometry import backproject, transform_points
from armlab.vision.pixel_world import world_to_pixel

RED = {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.0}
EMPTY_SPOT_M = (-0.12, 0.20)
HOVER_M = 0.12  # the gripper point this high on the camera ray: z ≈ 120 mm, as in the report


@pytest.fixture()
def station(tmp_path):
    """A synchronous, calibrated station on a fast simulation with one large red block; perception has seen
    the board with the arm at home."""
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=5), scene=Scene.from_dict({"objects": [RED]})) as cell:
        station = Station(cell.arm, cell.gripper, cell.camera, model=load_arm("rx200"), config=StationConfig(),
                          store=Store(tmp_path / "s.sqlite3"), sim=cell, synchronous=True)
        station.start()
        job = skills.calibrate(station)
        assert job.wait(60) and job.state == "succeeded", job.message
        station.fresh_perception()
        yield station
        station.close()


def truth(station, object_id: str) -> np.ndarray:
    return np.asarray(next(o for o in station.sim.truth()["objects"] if o["id"] == object_id)["position_m"], float)


def hover_on_ray(station, spot_m) -> np.ndarray:
    """Put the gripper (pointing down) on the true camera ray through spot_m at HOVER_M above the board and
    look again; returns the spot's pixel (through the calibration)."""
    spot = np.asarray(spot_m, float)
    camera = np.asarray(station.sim.truth()["camera"]["T_world_camera"], float)[:3, 3]  # ground truth
    t = (HOVER_M - spot[2]) / (camera[2] - spot[2])
    station.move_to(spot + t * (camera - spot), pitch_rad=math.pi / 2, wait=True)
    station.fresh_perception()
    return world_to_pixel(station.calibration, spot[None, :])[0]


def live_depth_point(station, uv) -> np.ndarray:
    """The world point of the newest frame's raw depth reading at uv (what the old code used)."""
    frame, _ = station.frames.get()
    cal = station.calibration
    depth_m = frame.depth_mm[int(round(uv[1])), int(round(uv[0]))] / 1000.0
    return transform_points(cal.T_world_camera, backproject(np.array([uv], float), np.array([depth_m]), cal.K, cal.dist))[0]


def test_a_board_pixel_under_the_arm_is_the_board(station):
    spot = np.array([*EMPTY_SPOT_M, 0.0])
    uv = hover_on_ray(station, spot)
    assert live_depth_point(station, uv)[2] > 0.06, "the arm does not cover the pixel: the test shows nothing"
    result = pixel_to_world(station, *uv)
    assert result["on"] in ("remembered", "board")
    assert np.abs(np.asarray(result["position_m"]) - spot).max() < 0.004, result


def test_a_block_under_the_arm_reads_its_top_seen_before(station):
    top = truth(station, "red") + [0.0, 0.0, 0.019]
    uv = hover_on_ray(station, top)
    assert live_depth_point(station, uv)[2] > top[2] + 0.04, "the arm does not cover the pixel"
    result = pixel_to_world(station, *uv)
    assert result["on"] == "remembered"
    assert np.abs(np.asarray(result["position_m"]) - top).max() < 0.005, result


def test_a_drop_clicked_under_the_arm_lands_where_the_pixel_points(station):
    job = skills.grab(station, position_m=list(truth(station, "red") + [0.0, 0.0, 0.019]))
    assert job.wait(120) and job.state == "succeeded", job.message
    spot = np.array([*EMPTY_SPOT_M, 0.0])
    uv = hover_on_ray(station, spot)
    job = skills.drop(station, pixel=tuple(uv))
    assert job.wait(120) and job.state == "succeeded", job.message
    landed = truth(station, "red")
    assert math.dist(landed[:2], spot[:2]) < 0.010, f"landed {landed} for the spot {spot}"
    assert abs(landed[2] - 0.019) < 0.004, "the block was let go in mid-air"


def test_a_grab_on_an_empty_spot_fails_saying_the_gripper_is_empty(station):
    uv = world_to_pixel(station.calibration, np.array([[*EMPTY_SPOT_M, 0.0]]))[0]
    job = skills.grab(station, pixel=tuple(uv))
    assert job.wait(120)
    assert job.state == "failed" and "nothing in the gripper" in job.message, (job.state, job.message)
    assert station.state is State.IDLE and station.held_block is None


def test_a_drop_with_an_empty_gripper_fails_and_moves_nothing(station):
    q0 = station.joints_rad()
    job = skills.drop(station, position_m=[*EMPTY_SPOT_M, 0.0])
    assert job.wait(60)
    assert job.state == "failed" and "empty" in job.message, (job.state, job.message)
    assert np.abs(station.joints_rad() - q0).max() < 2e-3
    assert station.state is State.IDLE
