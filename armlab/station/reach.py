"""Where this arm's gripper reaches on its workcell's board: top-down, only tilted, or not at all, on a grid of board
points at the height a block on the board is grasped at (the same approach solve the grabs use: armlab.motion.pick_place
solve_approach, from the grasp point and the approach point above it). Computed once per arm calibration and kept;
sent as a small grid of one letter per cell (the page draws it over the video and the top-down view).

A suction cup only works top-down, so its map has no tilted cells."""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from armlab.errors import Unreachable
from armlab.motion.end_effector import EndEffector
from armlab.motion.pick_place import solve_approach
from armlab.station.arm_info import station_end_effector
from armlab.workcell import load_workcell

REACH_STEP_M = 0.025  # the grid's spacing
TOP_DOWN, TILTED, OUT_OF_REACH = "T", "t", "."
LEGEND = {TOP_DOWN: "top-down", TILTED: "only tilted", OUT_OF_REACH: "out of reach"}


def grasp_height_m(workcell: Any, motion_config: Any, tool: EndEffector) -> float:
    """Where the tool point holds a large block standing on the board (plan_pick's grasp point)."""
    edge = workcell.block_edge_m("large")
    z = edge - tool.held_below_top_m(motion_config, edge)
    return float(max(z, motion_config.board_clearance_m, tool.lowest_grasp_m(motion_config)))


def classify(model: Any, motion_config: Any, tool: EndEffector, point_m, q_seed_rad) -> tuple[str, np.ndarray | None]:
    """(TOP_DOWN, TILTED or OUT_OF_REACH, the joints at the grasp point or None) for a grasp point (its approach point
    above included)."""
    point = np.asarray(point_m, float)
    near = point + np.array([0.0, 0.0, motion_config.approach_height_m])
    try:
        pitch, (q_point, _) = solve_approach(model, q_seed_rad, [point, near], None, motion_config.top_down_pitch_rad,
                                             tool.lowest_pitch_rad(motion_config))
    except Unreachable:
        return OUT_OF_REACH, None
    return (TOP_DOWN if pitch >= motion_config.top_down_pitch_rad - 1e-9 else TILTED), q_point


def horizontal_reach_m(model: Any, samples: int = 20000, seed: int = 0) -> float:
    """An upper bound of how far from the base axis (horizontally) the gripper point gets: the farthest of many joint
    samples within the limits, plus 5 %. A cell beyond it is out of reach without an IK attempt (a failing numeric IK
    is the slow part of the map)."""
    rng = np.random.default_rng(seed)
    lower, upper = np.asarray(model.lower_rad, float), np.asarray(model.upper_rad, float)
    q = rng.uniform(lower, upper, size=(samples, len(lower)))
    points = np.asarray(model.fk(q))[:, :3, 3]
    base = np.asarray(model.T_world_base, float)[:3, 3]
    return float(np.max(np.linalg.norm(points[:, :2] - base[:2], axis=1))) * 1.05


def reach_map(model: Any, motion_config: Any, tool: EndEffector, workcell: Any, step_m: float = REACH_STEP_M) -> dict:
    """The wire dict: {x0_m, y0_m, step_m, nx, ny, z_m, rows (ny strings of nx letters, row j at y0 + j·step), legend}."""
    (x_lo, x_hi), (y_lo, y_hi) = workcell.board.x_range_m, workcell.board.y_range_m
    nx, ny = int(np.floor((x_hi - x_lo) / step_m)) + 1, int(np.floor((y_hi - y_lo) / step_m)) + 1
    x0 = x_lo + 0.5 * ((x_hi - x_lo) - (nx - 1) * step_m)
    y0 = y_lo + 0.5 * ((y_hi - y_lo) - (ny - 1) * step_m)
    z = grasp_height_m(workcell, motion_config, tool)
    home = np.asarray(model.home_rad, float)
    started = time.monotonic()
    farthest = horizontal_reach_m(model)
    base = np.asarray(model.T_world_base, float)[:3, 3]
    rows = []
    for j in range(ny):
        row, seed = [], home
        for i in range(nx):  # each cell seeded by its neighbour's solution: a numeric IK converges in a few steps
            x, y = x0 + i * step_m, y0 + j * step_m
            if math.hypot(x - base[0], y - base[1]) > farthest:
                row.append(OUT_OF_REACH)
                seed = home
                continue
            letter, q = classify(model, motion_config, tool, (x, y, z), seed)
            row.append(letter)
            seed = q if q is not None else home
        rows.append("".join(row))
    return {"x0_m": float(x0), "y0_m": float(y0), "step_m": float(step_m), "nx": nx, "ny": ny, "z_m": z, "rows": rows,
            "legend": dict(LEGEND), "gripper": tool.name, "compute_s": round(time.monotonic() - started, 3)}


def cell_of(reach: dict, x_m: float, y_m: float) -> str:
    """The letter of the cell nearest (x, y) (OUT_OF_REACH off the grid)."""
    i = int(round((x_m - reach["x0_m"]) / reach["step_m"]))
    j = int(round((y_m - reach["y0_m"]) / reach["step_m"]))
    if not (0 <= i < reach["nx"] and 0 <= j < reach["ny"]):
        return OUT_OF_REACH
    return reach["rows"][j][i]


class ReachCache:
    """The station's reach map, computed on first use and again only when the arm's calibration changes."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._key: Any = None
        self._map: dict | None = None

    def get(self, station: Any) -> dict:
        key = (station.config.workcell, id(getattr(station.model, "calibration", None)))
        with self._lock:
            if self._map is None or key != self._key:
                workcell = load_workcell(station.config.workcell)
                self._map = reach_map(station.model, station.motion_config, station_end_effector(station), workcell)
                self._key = key
            return self._map
