"""Top faces cut by the image border. A tall stack's top can leave the camera's view (near the board's
-y edge, or far out in x, the taller the sooner), so only part of its square shows. The square still
follows from the edges that do show (never from the cut): the yaw from their directions, the side
from an axis whose two edges both show, and the centre from one shown edge per axis.

Pure functions on world points of the face's plane (metres); see blocks.py for where they are used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

COARSE_YAWS_RAD = np.radians(np.arange(-45.0, 45.0, 1.0))
FINE_YAWS_RAD = np.radians(np.arange(-1.0, 1.0001, 0.05))


@dataclass(frozen=True)
class ClippedSquare:
    """The square behind a cut face: centre (2,) world xy, side, yaw mod pi/2 in [-pi/4, pi/4).

    side_measured: the side came from an axis showing both edges (else from the only size class the
    shown extent allows). edge_residual_m: mean distance of the shown outline to the square's edges
    (a cube's face gives about a pixel; a disc or an arch far more)."""

    centre_xy: np.ndarray
    side_m: float
    yaw_rad: float
    side_measured: bool
    edge_residual_m: float


def on_image_border(pixels: np.ndarray, width: int, height: int, margin_px: float = 1.0) -> np.ndarray:
    """(N,) bool: which pixels (N, 2) lie within margin_px of the image's outermost rows or columns."""
    u, v = pixels[:, 0], pixels[:, 1]
    return (u <= margin_px) | (v <= margin_px) | (u >= width - 1 - margin_px) | (v >= height - 1 - margin_px)


def _rotated(points_xy: np.ndarray, yaws_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates (A, N) along u = (cos yaw, sin yaw) and v = (-sin yaw, cos yaw) for each yaw (A,)."""
    c, s = np.cos(yaws_rad)[:, None], np.sin(yaws_rad)[:, None]
    x, y = points_xy[None, :, 0], points_xy[None, :, 1]
    return x * c + y * s, y * c - x * s


def _edge_residuals(outline_xy: np.ndarray, shown: np.ndarray, yaws_rad: np.ndarray) -> np.ndarray:
    """(A,) mean distance of the shown outline points to the nearest side of the outline's bounding
    box in the frame of each yaw: small when the shown outline runs along a square's edges."""
    u, v = _rotated(outline_xy, yaws_rad)
    d = np.minimum(
        np.minimum(np.abs(u - u.min(axis=1, keepdims=True)), np.abs(u - u.max(axis=1, keepdims=True))),
        np.minimum(np.abs(v - v.min(axis=1, keepdims=True)), np.abs(v - v.max(axis=1, keepdims=True))),
    )
    return d[:, shown].mean(axis=1)


def _longest_run_m(positions_m: np.ndarray, max_gap_m: float) -> float:
    """Length of the longest stretch of positions (1-D) with no gap wider than max_gap_m: an edge's
    outline is one unbroken run, while the two ends of a cut square's sides are two short ones."""
    if positions_m.size == 0:
        return 0.0
    ordered = np.sort(positions_m)
    breaks = np.flatnonzero(np.diff(ordered) > max_gap_m)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [ordered.size - 1]])
    return float(np.max(ordered[ends] - ordered[starts]))


def fit_clipped_square(
    outline_xy: np.ndarray, shown: np.ndarray, pitch_m: float, edges_m: tuple[float, ...], size_tolerance: float,
    min_edge_m: float = 0.003,
) -> ClippedSquare | None:
    """The square whose part inside the image is the face with this outline.

    outline_xy: (N, 2) the face's outline (every boundary pixel's centre) on its plane; shown: (N,) bool,
    False where the outline runs along the image border. pitch_m: a pixel's size on the plane.
    edges_m: the possible sides (block sizes); size_tolerance: their relative tolerance.
    An edge counts as shown when shown outline points run along it, unbroken, over min_edge_m.
    None when the shown edges do not fix the square: an axis with neither edge shown, or no axis with
    both edges shown and a shown extent that more than one size fits.
    """
    if np.count_nonzero(shown) < 6:
        return None
    coarse = _edge_residuals(outline_xy, shown, COARSE_YAWS_RAD)
    best = float(COARSE_YAWS_RAD[int(np.argmin(coarse))])
    fine_yaws = best + FINE_YAWS_RAD
    fine = _edge_residuals(outline_xy, shown, fine_yaws)
    k = int(np.argmin(fine))
    yaw = (float(fine_yaws[k]) + math.pi / 4) % (math.pi / 2) - math.pi / 4
    u, v = (a[0] for a in _rotated(outline_xy, np.array([yaw])))
    tol = max(0.001, 1.5 * pitch_m)
    lows_highs, shown_edges = [], []
    for coord, other in ((u, v), (v, u)):
        lo, hi = float(coord.min()), float(coord.max())
        edges = []
        for extreme in (lo, hi):
            edges.append(_longest_run_m(other[shown & (np.abs(coord - extreme) <= tol)], 2.5 * pitch_m) >= min_edge_m)
        # Pixel centres sit half a pixel inside the face's edges.
        lows_highs.append((lo - 0.5 * pitch_m, hi + 0.5 * pitch_m))
        shown_edges.append(edges)
    full = [hi - lo for (lo, hi), (a, b) in zip(lows_highs, shown_edges) if a and b]
    if full:
        side, measured = float(math.sqrt(np.prod(full)) if len(full) == 2 else full[0]), True
    else:
        widest = max(hi - lo for lo, hi in lows_highs)
        fitting = [e for e in edges_m if widest <= e * (1.0 + size_tolerance)]
        if len(fitting) != 1:
            return None
        side, measured = float(fitting[0]), False
    centre_uv = []
    for (lo, hi), (lo_shown, hi_shown) in zip(lows_highs, shown_edges):
        if lo_shown and hi_shown:
            centre_uv.append(0.5 * (lo + hi))
        elif hi_shown:
            centre_uv.append(hi - 0.5 * side)
        elif lo_shown:
            centre_uv.append(lo + 0.5 * side)
        else:
            return None
    c, s = math.cos(yaw), math.sin(yaw)
    centre = np.array([centre_uv[0] * c - centre_uv[1] * s, centre_uv[0] * s + centre_uv[1] * c])
    return ClippedSquare(centre, side, yaw, measured, float(fine[k]))
