"""Touching cubes split from one face (armlab.vision.face_shape.split_touching) on synthetic footprints:
a real depth frays one cube's edge, a semicircle stays whole."""

from __future__ import annotations

import numpy as np

from armlab.vision.face_shape import Face, split_touching

PITCH_M = 0.001


def _face(points_xy: np.ndarray, top_m: float) -> Face:
    return Face(points_xy, top_m, np.zeros((0, 2)), np.zeros(2), len(points_xy), PITCH_M * PITCH_M)


def _grid(x_m: tuple[float, float], y_m: tuple[float, float]) -> np.ndarray:
    xs = np.arange(x_m[0] + PITCH_M / 2, x_m[1], PITCH_M)
    ys = np.arange(y_m[0] + PITCH_M / 2, y_m[1], PITCH_M)
    return np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)


def test_two_touching_cubes_split_when_the_depth_frays_one_of_them(cfg):
    """Two large cubes edge to edge; the second's outer edges lose pixels as the realistic depth's holes
    and flying pixels take them (its part fills ~0.77 of its rectangle, the pair ~0.88): still two cubes."""
    edge = cfg.blocks.large_size_m
    top = cfg.blocks.large_size_m  # one cube high
    left, right = _grid((0.0, edge), (0.0, edge)), _grid((edge, 2 * edge), (0.0, edge))
    rng = np.random.default_rng(3)
    outer = (right[:, 0] > 2 * edge - 0.004) | (right[:, 1] < 0.004) | (right[:, 1] > edge - 0.004)
    frayed = right[~outer | (rng.random(len(right)) < 0.3)]
    parts = split_touching(_face(np.vstack([left, frayed]), top), cfg)
    assert len(parts) == 2
    centres = sorted(p.points_xy.mean(axis=0)[0] for p in parts)
    assert abs(centres[0] - edge / 2) < 0.004 and abs(centres[1] - 1.5 * edge) < 0.006


def test_a_semicircle_is_not_split_into_quarter_discs(cfg):
    radius = cfg.blocks.large_size_m
    pts = _grid((-radius, radius), (0.0, radius))
    semicircle = pts[np.hypot(pts[:, 0], pts[:, 1]) <= radius]
    assert len(split_touching(_face(semicircle, cfg.blocks.large_size_m), cfg)) == 1


def test_a_face_at_a_height_no_pile_has_is_not_clustered(cfg, monkeypatch):
    """Two cubes' footprint 12 mm above the board (pliers' handles, a cable: no pile of cubes is that high):
    no part could be a cube, so it stays whole without any k-means run (the same footprint at a cube's
    height splits, test above)."""
    import armlab.vision.face_shape as face_shape

    def no_kmeans(*args, **kwargs):
        raise AssertionError("k-means run for a face no cube can be part of")

    monkeypatch.setattr(face_shape.cv2, "kmeans", no_kmeans)
    edge = cfg.blocks.large_size_m
    pair = np.vstack([_grid((0.0, edge), (0.0, edge)), _grid((edge, 2 * edge), (0.0, edge))])
    assert len(split_touching(_face(pair, 0.012), cfg)) == 1
