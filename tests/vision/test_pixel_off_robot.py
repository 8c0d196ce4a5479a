"""pixel_to_world_off_robot and the perception's surface memory on synthetic data (a camera 1 m above the
board looking straight down; depth drawn by hand): the robot's own readings are never used, the depth
remembered there is, else the board plane."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.station.perception import surface_off_robot
from armlab.vision.calibration import Calibration
from armlab.vision.pixel_world import pixel_to_world_off_robot

W, H = 160, 120
K = np.array([[100.0, 0.0, 80.0], [0.0, 100.0, 60.0], [0.0, 0.0, 1.0]])
# camera 1 m above the world origin looking down: camera z = world -z, camera x = world x, camera y = world -y
T_WORLD_CAMERA = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, 1.0], [0, 0, 0, 1.0]])


@pytest.fixture()
def cal():
    return Calibration(T_world_camera=T_WORLD_CAMERA, K=K, dist=np.zeros(5), width=W, height=H, reprojection_error_px=0.1)


class Slab:
    """A 'robot' occupying z > 0.1 m everywhere (a horizontal slab between the camera and the board)."""

    @staticmethod
    def contains(points):
        return np.asarray(points)[:, 2] > 0.1


def board_depth(mm: int = 1000) -> np.ndarray:
    return np.full((H, W), mm, np.uint16)


def test_depth_off_the_robot_is_used(cal):
    depth = board_depth(962)  # a 38 mm block top everywhere
    point, on = pixel_to_world_off_robot(cal, 80, 60, depth, Slab())
    assert on == "depth" and point == pytest.approx([0.0, 0.0, 0.038], abs=1e-6)


def test_the_robot_s_reading_falls_back_to_the_remembered_surface_then_the_board(cal):
    arm = board_depth(880)  # 120 mm above the board: inside the slab
    point, on = pixel_to_world_off_robot(cal, 100, 40, arm, Slab(), remembered_depth_mm=board_depth(962))
    assert on == "remembered" and point[2] == pytest.approx(0.038, abs=1e-6)
    point, on = pixel_to_world_off_robot(cal, 100, 40, arm, Slab(), remembered_depth_mm=np.zeros((H, W), np.uint16))
    assert on == "board" and point[2] == pytest.approx(0.0, abs=1e-9)
    assert point[:2] == pytest.approx([0.2, 0.2], abs=1e-9)  # (100 - 80) / 100 m right, (60 - 40) / 100 m ahead


def test_a_window_half_on_the_robot_uses_the_other_half(cal):
    depth = board_depth(1000)
    depth[:, 81:] = 880  # the arm's edge passes just right of the pixel
    point, on = pixel_to_world_off_robot(cal, 80, 60, depth, Slab())
    assert on == "depth" and point[2] == pytest.approx(0.0, abs=1e-6)


def test_the_surface_memory_keeps_what_the_robot_covers():
    first = surface_off_robot(board_depth(962), np.zeros((H, W), bool), None)
    mask = np.zeros((H, W), bool)
    mask[10:20, 10:20] = True
    second = surface_off_robot(board_depth(880), mask, first)
    assert (second[mask] == 962).all() and (second[~mask] == 880).all()
    assert (surface_off_robot(board_depth(880), mask, None)[mask] == 0).all()  # never seen: no reading
    assert surface_off_robot(None, mask, first) is None
