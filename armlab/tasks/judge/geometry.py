"""What every event's judging shares (DESIGN §7): upright, on the board, columns, the total-least-squares
line and distances in x-y, and the rainbow order. Objects are SceneObjects or truth dicts."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene import COLORS, SceneObject
from armlab.scene.model import WORKCELL_BOUND_M

UPRIGHT_MAX_TILT_RAD = math.radians(15.0)
SURFACE_TOLERANCE_M = 0.006  # bottom face to the board, or to the top of the block below
STACK_XY_TOLERANCE_M = 0.015
RAINBOW = COLORS  # red, orange, yellow, green, blue, violet: rank 0..5


def as_object(obj, workcell: str | None = None) -> SceneObject:
    """A SceneObject, or a truth dict read with `workcell`'s sizes (None = the default workcell)."""
    return obj if isinstance(obj, SceneObject) else SceneObject.from_dict(within_bound(obj), workcell)


def within_bound(data):
    """A truth object with its position clamped to the scene bound: a body pushed off the simulated table falls
    on without end, and is judged where it is, far off the board, not refused as a malformed scene."""
    if not isinstance(data, Mapping) or not isinstance(data.get("position_m"), (list, tuple)):
        return data
    bound = WORKCELL_BOUND_M - 1e-6
    position = [min(bound, max(-bound, x)) if isinstance(x, (int, float)) and math.isfinite(x) else x for x in data["position_m"]]
    return {**data, "position_m": position}


def tilt_rad(obj) -> float:
    """Angle between the object's body z axis and world z."""
    _w, x, y, _z = as_object(obj).quat_wxyz
    return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y))))


def upright(obj) -> bool:
    """Body z axis within 15° of world z (a SceneObject or a truth dict)."""
    return tilt_rad(obj) <= UPRIGHT_MAX_TILT_RAD + 1e-12


def bottom_z_m(obj: SceneObject) -> float:
    return obj.position_m[2] - 0.5 * obj.dimensions_m[2]


def top_z_m(obj: SceneObject) -> float:
    return obj.position_m[2] + 0.5 * obj.dimensions_m[2]


def centre_xy(obj: SceneObject) -> np.ndarray:
    return np.array(obj.position_m[:2])


def on_board(obj) -> bool:
    """Bottom face (centre z - edge/2) within ±6 mm of the board surface z = 0."""
    return abs(bottom_z_m(as_object(obj))) <= SURFACE_TOLERANCE_M + 1e-12


def columns(objects, workcell: str | None = None) -> list[tuple[SceneObject, ...]]:
    """Stacks of the given blocks, each bottom first: a column starts with a block on the board, and a block joins
    the column whose top block's centre is within 15 mm (xy) and whose top is within ±6 mm of its bottom.
    Truth dicts are read with `workcell`'s block sizes (None = the default workcell)."""
    blocks = [obj for obj in (as_object(o, workcell) for o in objects) if obj.type == "block"]
    stacks = [[block] for block in blocks if on_board(block)]
    rest = sorted((b for b in blocks if not on_board(b)), key=lambda b: (bottom_z_m(b), b.id))
    for block in rest:
        best: tuple[float, list[SceneObject]] | None = None
        for stack in stacks:
            top = stack[-1]
            distance = float(np.linalg.norm(centre_xy(block) - centre_xy(top)))
            if distance <= STACK_XY_TOLERANCE_M and abs(bottom_z_m(block) - top_z_m(top)) <= SURFACE_TOLERANCE_M:
                if best is None or distance < best[0]:
                    best = (distance, stack)
        if best is not None:
            best[1].append(block)
    return [tuple(stack) for stack in stacks]


def tls_line(points) -> tuple[np.ndarray, np.ndarray]:
    """Total-least-squares line through points (N, 2) or (N, 3), xy used: (centroid (2,), unit direction (2,)).
    The direction's sign is canonical (x > 0, or y > 0 when vertical); callers read the line both ways."""
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[0] < 1 or pts.shape[1] not in (2, 3) or not np.all(np.isfinite(pts)):
        raise InvalidInput(f"tls_line needs (N, 2) or (N, 3) finite points with N >= 1, got shape {pts.shape}")
    xy = pts[:, :2]
    centre = xy.mean(axis=0)
    _u, _s, vt = np.linalg.svd(xy - centre)
    direction = vt[0] / np.linalg.norm(vt[0])
    if direction[0] < 0.0 or (direction[0] == 0.0 and direction[1] < 0.0):
        direction = -direction
    return centre, direction


def line_distance_m(point: np.ndarray, centre: np.ndarray, direction: np.ndarray) -> float:
    offset = point - centre
    return abs(float(direction[0] * offset[1] - direction[1] * offset[0]))


def segment_distance_m(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    span = end - start
    length_sq = float(span @ span)
    t = 0.0 if length_sq == 0.0 else min(1.0, max(0.0, float((point - start) @ span) / length_sq))
    return float(np.linalg.norm(point - (start + t * span)))
