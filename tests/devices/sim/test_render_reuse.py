"""The simulated camera rasterises a still scene once and copies that picture for the frames after it (a
1280x720 render costs ~50 ms of CPU without a GPU, at every frame of every running station), and never shows an
old picture once anything it draws has changed: the arm, the checkerboard, the camera, a colour, a light."""

from __future__ import annotations

import numpy as np
import pytest

from armlab.devices.arm import JointTrajectory
from armlab.devices.sim import SimWorkcell, SimWorkcellConfig


@pytest.fixture()
def cell():
    with SimWorkcell(SimWorkcellConfig(realtime=False, seed=0)) as started:
        started.start()
        started.step(0.5)  # the blocks settle
        yield started


def _differs(a, b) -> bool:
    return not (np.array_equal(a.rgb, b.rgb) and np.array_equal(a.depth_m, b.depth_m))


def test_a_still_scene_is_rasterised_once_and_shows_the_same_picture(cell):
    first = cell.render_raw()
    rasterised, _ = cell._renderer().draw_counts
    cell.step(1.0)  # physics runs on; nothing moves
    frames = [cell.render_raw() for _ in range(3)]
    assert cell._renderer().draw_counts == (rasterised, 3)
    assert not any(_differs(first, frame) for frame in frames)
    frames[0].rgb[:] = 0  # each frame is the caller's own: spoiling one spoils no later one
    assert not _differs(first, cell.render_raw())


def _move_the_arm(cell):
    start = cell.arm_positions()
    end = start + np.array([0.3, 0.0, 0.0, 0.0, 0.0])
    cell.arm.command_trajectory(JointTrajectory(np.array([0.0, 1.0]), np.vstack([start, end])))
    cell.step(1.5)


def _recolour_a_link(cell):
    with cell.lock:
        cell._model.geom_rgba[cell._model.geom("shoulder_capsule").id] = [1.0, 0.0, 1.0, 1.0]


def _dim_the_light(cell):
    with cell.lock:
        cell._model.light_diffuse[:] *= 0.5


CHANGES = {
    "arm moved": _move_the_arm,
    "checkerboard shown": lambda cell: cell.place_checkerboard([0.0, 0.2, 0.3]),
    "camera knocked": lambda cell: cell.knock_camera([0.01, 0.0, 0.0], [0.0, 0.0, 0.02]),
    "link recoloured": _recolour_a_link,
    "light dimmed": _dim_the_light,
}


@pytest.mark.parametrize("change", list(CHANGES))
def test_any_change_is_drawn_anew(cell, change):
    before = cell.render_raw()
    assert not _differs(before, cell.render_raw())  # the picture is reused while nothing changes
    rasterised, _ = cell._renderer().draw_counts
    CHANGES[change](cell)
    after = cell.render_raw()
    assert cell._renderer().draw_counts[0] == rasterised + 1
    assert _differs(before, after), f"{change}: the camera showed the picture from before the change"
