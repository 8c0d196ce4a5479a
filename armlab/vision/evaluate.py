"""Scoring perception against simulator ground truth (for tests and bench/perception.py only; the
detection code never sees truth). Truth format: SimWorkcell.truth()."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from armlab.vision.blocks import Block
from armlab.vision.calibration import Calibration
from armlab.vision.geometry import invert_transform
from armlab.vision.pixel_world import pixel_to_world
from armlab.workcell import Workcell, load_workcell


@dataclass(frozen=True)
class ExpectedTop:
    """The top object of one pile as the camera should report it."""

    object_id: str
    type: str
    color: str
    size: str | None
    top_center_m: np.ndarray
    yaw_rad: float
    stack_level: int
    aruco_id: int | None
    resting: bool = True  # flat on the board (not tipped over, not fallen off the board)


def _yaw_mod_quarter(yaw_rad: float) -> float:
    return (yaw_rad + math.pi / 4) % (math.pi / 2) - math.pi / 4


def yaw_error_rad(a: float, b: float) -> float:
    """Smallest difference between two yaws modulo 90 degrees."""
    d = (a - b) % (math.pi / 2)
    return min(d, math.pi / 2 - d)


def expected_tops(truth: dict, pile_radius_m: float = 0.012, workcell: Workcell | None = None) -> list[ExpectedTop]:
    """Top object of every pile (objects whose centres are within pile_radius_m horizontally); block
    sizes and the board from the workcell config (default: the default workcell)."""
    workcell = workcell or load_workcell()
    objects = sorted(truth["objects"], key=lambda o: o["position_m"][2])
    piles: list[list[dict]] = []
    for obj in objects:
        for pile in piles:
            if math.dist(pile[0]["position_m"][:2], obj["position_m"][:2]) < pile_radius_m:
                pile.append(obj)
                break
        else:
            piles.append([obj])
    tops = []
    for pile in piles:
        top = pile[-1]
        if top["type"] == "block":
            half = workcell.block_edge_m(top["size"]) / 2
        else:
            half = 0.0
        centre = np.array(top["position_m"], dtype=float) + np.array([0.0, 0.0, half])
        w, x, y, z = top["quat_wxyz"]
        up_z = 1.0 - 2.0 * (x * x + y * y)  # world z of the body's z axis
        on_board = workcell.board.contains(float(centre[0]), float(centre[1]))
        tops.append(
            ExpectedTop(top["id"], top["type"], top["color"], top.get("size"), centre,
                        _yaw_mod_quarter(float(top["yaw_rad"])), len(pile), top.get("aruco_id"),
                        resting=bool(on_board and up_z > math.cos(math.radians(10.0))))
        )
    return tops


def hidden_tops(tops: list[ExpectedTop], truth: dict, depth_mm: np.ndarray, margin_mm: float = 8.0,
                workcell: Workcell | None = None) -> set[str]:
    """Ids of block tops that something (the arm) hides in part: a corner or the centre of the top face
    shows a depth reading well in front of the face."""
    workcell = workcell or load_workcell()
    cam = truth["camera"]
    K = np.asarray(cam["K"], dtype=float)
    T_camera_world = invert_transform(np.asarray(cam["T_world_camera"], dtype=float))
    hidden = set()
    for top in tops:
        if top.type != "block":
            continue
        h = workcell.block_edge_m(top.size) / 2 * 0.8
        c, s = math.cos(top.yaw_rad), math.sin(top.yaw_rad)
        offsets = [(0.0, 0.0)] + [(sx * h * c - sy * h * s, sx * h * s + sy * h * c) for sx in (-1, 1) for sy in (-1, 1)]
        for dx, dy in offsets:
            p = T_camera_world @ np.array([top.top_center_m[0] + dx, top.top_center_m[1] + dy, top.top_center_m[2], 1.0])
            u, v = (K @ (p[:3] / p[2]))[:2]
            ui, vi = int(round(u)), int(round(v))
            if 0 <= vi < depth_mm.shape[0] and 0 <= ui < depth_mm.shape[1]:
                d = float(depth_mm[vi, ui])
                if 0 < d < p[2] * 1000.0 - margin_mm:
                    hidden.add(top.object_id)
                    break
    return hidden


@dataclass
class SceneScore:
    """Counts and errors for one scene (lists are per matched block)."""

    true_positives: int = 0
    false_positives: int = 0
    false_negatives: int = 0
    color_correct: int = 0
    size_correct: int = 0
    level_correct: int = 0
    tag_correct: int = 0
    tag_total: int = 0
    distractors: int = 0
    distractors_rejected: int = 0
    hidden: int = 0
    hidden_flagged: int = 0
    excluded: int = 0
    visible_flagged: int = 0  # fully visible blocks wrongly flagged occluded
    position_errors_m: list | None = None
    yaw_errors_rad: list | None = None
    failures: list | None = None

    def __post_init__(self) -> None:
        self.position_errors_m = [] if self.position_errors_m is None else self.position_errors_m
        self.yaw_errors_rad = [] if self.yaw_errors_rad is None else self.yaw_errors_rad
        self.failures = [] if self.failures is None else self.failures


def score_blocks(blocks: list[Block], truth: dict, depth_mm: np.ndarray, match_radius_m: float = 0.015) -> SceneScore:
    """Match cube detections to pile tops; hidden (arm-occluded) tops count only for the occlusion flag."""
    tops = expected_tops(truth)
    hidden = hidden_tops(tops, truth, depth_mm)
    score = SceneScore()
    cubes = [b for b in blocks if b.is_cube]
    used: set[int] = set()
    for top in tops:
        dists = [math.dist(b.position_m[:2], top.top_center_m[:2]) if i not in used else math.inf for i, b in enumerate(cubes)]
        best = int(np.argmin(dists)) if dists else -1
        matched = best >= 0 and dists[best] < match_radius_m
        if not top.resting:  # tipped over or off the board: not a scene the station is asked to read
            score.excluded += 1
            used.update(i for i, b in enumerate(cubes) if math.dist(b.position_m[:2], top.top_center_m[:2]) < 0.03)
            continue
        if top.type != "block":
            score.distractors += 1
            if matched:
                used.add(best)  # counted as a false positive below
                score.failures.append(f"distractor {top.type} reported as a cube")
            else:
                score.distractors_rejected += 1
            continue
        if top.object_id in hidden:
            score.hidden += 1
            near = [b for b in blocks if math.dist(b.position_m[:2], top.top_center_m[:2]) < 0.03]
            if not near or any(b.occluded for b in near):
                score.hidden_flagged += 1
            if matched:
                used.add(best)  # neither credited nor blamed: the occlusion flag is what counts here
            continue
        if not matched:
            score.false_negatives += 1
            score.failures.append(f"missed {top.color} {top.size} at {np.round(top.top_center_m * 1000).tolist()} mm")
            continue
        used.add(best)
        block = cubes[best]
        score.true_positives += 1
        score.color_correct += block.color == top.color
        score.size_correct += block.size == top.size
        score.level_correct += block.stack_level == top.stack_level
        score.visible_flagged += bool(block.occluded)
        if top.aruco_id is not None:
            score.tag_total += 1
            score.tag_correct += block.aruco_id == top.aruco_id
            if block.aruco_id != top.aruco_id:
                score.failures.append(f"tag {top.aruco_id} on the {top.color} {top.size} block read as {block.aruco_id}")
        if block.color != top.color or block.size != top.size or block.stack_level != top.stack_level:
            score.failures.append(
                f"{top.color} {top.size} L{top.stack_level} seen as {block.color} {block.size} L{block.stack_level}"
            )
        score.position_errors_m.append(float(np.linalg.norm(block.position_m - top.top_center_m)))
        score.yaw_errors_rad.append(yaw_error_rad(block.yaw_rad, top.yaw_rad))
    for i, block in enumerate(cubes):
        if i not in used:
            score.false_positives += 1
            score.failures.append(f"extra {block.color} {block.size} at {np.round(block.position_m * 1000).tolist()} mm")
    return score


def click_grid_errors(cal: Calibration, truth: dict, step_m: float = 0.025,
                      x_range_m=None, y_range_m=None, workcell: Workcell | None = None) -> np.ndarray:
    """Click-to-world errors (m) over a dense grid of board points: each point is projected through the
    true camera to the pixel a user would click, then mapped back through the calibration (ray-plane).
    Default ranges: the workcell's grid in x, its board inset by 25 mm in y."""
    board = (workcell or load_workcell()).board
    x_range_m = board.grid.x_m if x_range_m is None else x_range_m
    y_range_m = (board.y_range_m[0] + 0.025, board.y_range_m[1] - 0.025) if y_range_m is None else y_range_m
    cam = truth["camera"]
    K = np.asarray(cam["K"], dtype=float)
    T_camera_world = invert_transform(np.asarray(cam["T_world_camera"], dtype=float))
    xs = np.arange(x_range_m[0], x_range_m[1] + 1e-9, step_m)
    ys = np.arange(y_range_m[0], y_range_m[1] + 1e-9, step_m)
    errors = []
    for x in xs:
        for y in ys:
            p = T_camera_world @ np.array([x, y, 0.0, 1.0])
            u, v = (K @ (p[:3] / p[2]))[:2]
            if not (0 <= u < cam["width"] - 1 and 0 <= v < cam["height"] - 1):
                continue
            errors.append(np.linalg.norm(pixel_to_world(cal, u, v, plane_z_m=0.0) - np.array([x, y, 0.0])))
    return np.array(errors)
