"""fit_clipped_square: the square behind a top face that the image border cuts, from the edges that
show. Faces are rasterised here from exact squares and cut by exact lines, so the truth is known."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from armlab.vision.clipped_face import fit_clipped_square, on_image_border

LARGE, SMALL = 0.038, 0.025
PITCH_M = 0.0006  # a pixel on a tall tower's top, about


def cut_face(centre, side, yaw, keep, pitch=PITCH_M):
    """(outline_xy, shown) of the square (centre, side, yaw) rasterised at pitch and cut to keep(x, y);
    outline points within 1.5 pixels of the cut are not shown (they lie on the 'image border')."""
    n = int(0.12 / pitch)
    origin = np.asarray(centre) - 0.5 * n * pitch
    gx, gy = np.meshgrid(np.arange(n) * pitch + origin[0], np.arange(n) * pitch + origin[1])
    c, s = math.cos(yaw), math.sin(yaw)
    du, dv = (gx - centre[0]) * c + (gy - centre[1]) * s, -(gx - centre[0]) * s + (gy - centre[1]) * c
    square = (np.abs(du) <= side / 2) & (np.abs(dv) <= side / 2)
    mask = (square & keep(gx, gy, 0.0)).astype(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    px = max(contours, key=cv2.contourArea).reshape(-1, 2)
    xy = origin + px * pitch
    shown = keep(xy[:, 0], xy[:, 1], 1.5 * pitch)
    return xy, shown


def everything(x, y, margin):
    return np.ones(np.shape(x), bool)


def above(limit_y):
    """Keep y > limit_y: the image's bottom border cuts a tower's top near the board's -y edge."""
    return lambda x, y, margin: np.asarray(y) > limit_y + margin


def fit(outline, shown):
    return fit_clipped_square(outline, shown, PITCH_M, (LARGE, SMALL), 0.22)


@pytest.mark.parametrize("yaw", [0.0, 0.3, -0.7])
def test_a_whole_face_gives_its_square(yaw):
    centre = np.array([0.1, -0.15])
    result = fit(*cut_face(centre, LARGE, yaw, everything))
    assert np.linalg.norm(result.centre_xy - centre) < 0.0004
    assert result.side_m == pytest.approx(LARGE, abs=0.0008) and result.side_measured
    assert abs(result.yaw_rad - ((yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4)) < math.radians(1.0)
    assert result.edge_residual_m < 0.5 * PITCH_M


@pytest.mark.parametrize("yaw", [0.0, 0.25, -0.4])
@pytest.mark.parametrize("shown_fraction", [0.2, 0.6])
def test_a_face_cut_across_comes_from_its_shown_edges(yaw, shown_fraction):
    """Part of the face (80 or 40 %) beyond the border: the edges that show still fix it."""
    centre = np.array([0.086, -0.15])
    keep = above(centre[1] + LARGE / 2 - shown_fraction * LARGE)
    result = fit(*cut_face(centre, LARGE, yaw, keep))
    assert result is not None
    assert np.linalg.norm(result.centre_xy - centre) < 0.0008
    assert result.side_m == pytest.approx(LARGE, abs=0.001)
    assert result.side_measured or yaw != 0.0  # square to the cut, both sides show; turned, maybe one corner
    assert abs(result.yaw_rad - yaw) < math.radians(1.5)


def test_a_corner_cut_by_two_borders_takes_the_only_size_that_fits():
    """Only a 34 x 34 mm corner shows: too big for a small block, so a large one, centred from the
    two shown edges."""
    centre = np.array([0.3, 0.1])
    limit = centre + LARGE / 2 - 0.034
    keep = lambda x, y, m: (np.asarray(x) > limit[0] + m) & (np.asarray(y) > limit[1] + m)  # noqa: E731
    result = fit(*cut_face(centre, LARGE, 0.0, keep))
    assert result is not None and not result.side_measured and result.side_m == LARGE
    assert np.linalg.norm(result.centre_xy - centre) < 0.0008


def test_a_small_corner_or_a_lone_corner_fixes_nothing():
    centre = np.array([0.3, 0.1])
    # A 20 x 20 mm corner of a large block: a small block fits it too.
    limit = centre + LARGE / 2 - 0.020
    corner = lambda x, y, m: (np.asarray(x) > limit[0] + m) & (np.asarray(y) > limit[1] + m)  # noqa: E731
    assert fit(*cut_face(centre, LARGE, 0.0, corner)) is None
    # A rotated square cut so that only one corner's two half-edges show: no axis shows a full edge
    # and its extent is small.
    tip = lambda x, y, m: np.asarray(y) > centre[1] + 0.012 + m  # noqa: E731
    assert fit(*cut_face(centre, LARGE, math.radians(40.0), tip)) is None


def test_on_image_border():
    pixels = np.array([[0.0, 300.0], [1.0, 5.0], [640.0, 719.0], [1279.0, 10.0], [640.0, 360.0], [3.0, 3.0]])
    assert on_image_border(pixels, 1280, 720, 1.0).tolist() == [True, True, True, True, False, False]


@pytest.mark.parametrize("diameter", [LARGE, SMALL])
@pytest.mark.parametrize("cut_m", [-0.005, 0.004])
def test_a_cut_disc_is_not_a_square(diameter, cut_m):
    """A cylinder's top cut by the border: its round outline lies far from any square's edges
    (blocks.py calls a cut face a cube only below MAX_EDGE_RESIDUAL of the edge)."""
    from armlab.vision.face_shape import MAX_EDGE_RESIDUAL

    centre = np.array([0.086, -0.15])
    n = int(0.12 / PITCH_M)
    origin = centre - 0.5 * n * PITCH_M
    gx, gy = np.meshgrid(np.arange(n) * PITCH_M + origin[0], np.arange(n) * PITCH_M + origin[1])
    keep = above(centre[1] + cut_m)
    mask = ((np.hypot(gx - centre[0], gy - centre[1]) <= diameter / 2) & keep(gx, gy, 0.0)).astype(np.uint8)
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    xy = origin + max(contours, key=cv2.contourArea).reshape(-1, 2) * PITCH_M
    result = fit(xy, keep(xy[:, 0], xy[:, 1], 1.5 * PITCH_M))
    assert result is None or result.edge_residual_m > MAX_EDGE_RESIDUAL * diameter
