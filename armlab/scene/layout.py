"""Random placement for the scene generators: the board regions objects may stand in (reach, board margins,
tag and spot keep-outs), piles of objects stacked on one footprint, and placing piles without overlap."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.scene.model import Feeder, Scene, SceneObject, as_workcell, object_dimensions_m, quat_from_yaw
from armlab.workcell import Workcell
from armlab.workcell.spots import DEFAULT_SCENE_REACH_M

# Generator choices (not workcell facts): the margin kept from the board edges (x, y), the tag keep-out and
# the gap between piles. Where a top-down grasp reaches comfortably (radius from the base axis) is the
# workcell's scene.reach_m (the RX200's 0.13-0.36 m by default).
REACH_MIN_M, REACH_MAX_M = DEFAULT_SCENE_REACH_M
BOARD_MARGIN_M = (0.02, 0.015)
TAG_KEEPOUT_M = 0.035
SPACING_MARGIN_M = 0.03  # free gap between footprints so fingers fit between neighbours


@dataclass(frozen=True)
class Region:
    """Where the bottom object of each footprint may be centred (also within reach and on the board,
    clear of the board tags and of the keep-out circles (x, y, radius) and rectangles (x0, x1, y0, y1))."""

    x_m: tuple[float, float]
    y_m: tuple[float, float]
    keepout_circles: tuple[tuple[float, float, float], ...] = ()
    keepout_rects: tuple[tuple[float, float, float, float], ...] = ()

    def contains(self, x: float, y: float, radius: float, workcell: Workcell) -> bool:
        r = math.hypot(x, y)
        reach_min_m, reach_max_m = workcell.scene.reach_m
        if not (reach_min_m <= r <= reach_max_m):
            return False
        if not (self.x_m[0] + radius <= x <= self.x_m[1] - radius and self.y_m[0] + radius <= y <= self.y_m[1] - radius):
            return False
        (bx0, bx1), (by0, by1) = workcell.board.x_range_m, workcell.board.y_range_m
        mx, my = BOARD_MARGIN_M
        if not (bx0 + mx + radius <= x <= bx1 - mx - radius and by0 + my + radius <= y <= by1 - my - radius):
            return False
        if any(math.dist((x, y), (cx, cy)) < cr + radius for cx, cy, cr in self.keepout_circles):
            return False
        if any(x0 - radius < x < x1 + radius and y0 - radius < y < y1 + radius for x0, x1, y0, y1 in self.keepout_rects):
            return False
        return all(math.dist((x, y), tag) >= TAG_KEEPOUT_M + radius for tag in workcell.board_tags.centres_m.values())


def board_regions(workcell: Workcell) -> dict[str, Region]:
    """The generators' regions: y > 0 (with a strip kept free), the tag rectangle, the whole board."""
    tag_x = [x for x, _ in workcell.board_tags.centres_m.values()]
    tag_y = [y for _, y in workcell.board_tags.centres_m.values()]
    board_x, board_y = workcell.board.x_range_m, workcell.board.y_range_m
    return {
        "positive_half": Region(x_m=board_x, y_m=(0.04, board_y[1])),
        "tag_rectangle": Region(x_m=(min(tag_x), max(tag_x)), y_m=(min(tag_y), max(tag_y))),
        "whole_board": Region(x_m=board_x, y_m=board_y),
    }


def stack_objects(
    pile: list[tuple[str, str | None, str]], x: float, y: float, yaw: float, first_index: int,
    aruco_ids: list[int | None] | None = None, workcell: Workcell | None = None,
) -> list[SceneObject]:
    """Objects of one footprint, bottom first (pile: (type, size, colour)); optional ArUco id per object."""
    workcell = as_workcell(workcell)
    objects = []
    z_bottom = 0.0
    for offset, (obj_type, size, color) in enumerate(pile):
        height = object_dimensions_m(obj_type, size, workcell)[2]
        prefix = "block" if obj_type == "block" else obj_type
        objects.append(
            SceneObject(
                id=f"{prefix}_{first_index + offset}",
                type=obj_type,
                color=color,
                size=size,
                position_m=(x, y, z_bottom + 0.5 * height),
                quat_wxyz=quat_from_yaw(yaw),
                aruco_id=aruco_ids[offset] if aruco_ids else None,
                workcell=workcell.name,
            )
        )
        z_bottom += height
    return objects


def place_piles(piles: list[list[tuple]], region: Region, rng: np.random.Generator,
                 workcell: Workcell | None = None, feeder: Feeder | None = None) -> Scene:
    """Place each pile (a stack of 1+ objects, bottom first) at a random reachable, non-overlapping spot.
    A pile item is (type, size, colour) or (type, size, colour, aruco_id)."""
    workcell = as_workcell(workcell)
    reach_max_m = workcell.scene.reach_m[1]
    for _attempt in range(50):
        placed: list[tuple[float, float, float]] = []  # x, y, footprint radius
        objects: list[SceneObject] = []
        ok = True
        for pile in piles:
            radius = max(0.5 * math.hypot(*object_dimensions_m(item[0], item[1], workcell)[:2]) for item in pile)
            for _try in range(400):
                x = rng.uniform(-reach_max_m, reach_max_m)
                y = rng.uniform(-reach_max_m, reach_max_m)
                if not region.contains(x, y, radius, workcell):
                    continue
                if all(math.dist((x, y), (px, py)) >= radius + pr + SPACING_MARGIN_M for px, py, pr in placed):
                    break
            else:
                ok = False
                break
            yaw = float(rng.uniform(-math.pi / 4.0, math.pi / 4.0))
            placed.append((x, y, radius))
            ids = [item[3] if len(item) > 3 else None for item in pile]
            objects.extend(stack_objects([item[:3] for item in pile], x, y, yaw, len(objects), ids, workcell))
        if ok:
            return Scene(objects=tuple(objects), feeder=feeder, workcell=workcell.name)
    raise RuntimeError("could not place the scene's objects without overlap; ask for fewer objects")


def block_items(sizes: list[str], colors: list[str]) -> list[tuple[str, str | None, str]]:
    """Pile items (type, size, colour) of blocks."""
    return [("block", size, color) for size, color in zip(sizes, colors)]


def into_piles(items: list, max_height: int, stack_probability: float, rng: np.random.Generator) -> list[list]:
    """Group items into piles of up to max_height (larger blocks at the bottom of each pile)."""
    order = list(rng.permutation(len(items)))
    piles: list[list] = []
    while order:
        height = 1
        while height < min(max_height, len(order)) and rng.random() < stack_probability:
            height += 1
        chosen = [items[i] for i in order[:height]]
        order = order[height:]
        chosen.sort(key=lambda item: 0 if item[1] in ("large", None) else 1)
        piles.append(chosen)
    return piles
