"""The operator's grab and drop planned around what the station knows is on the board (issue 21: a grab on
empty board 57 mm from a stack came down with the fingers open across it and knocked it over).

Every detected block and stack (the newest detections) is a box from the board to its top, as the jobs see
them (armlab.motion.clearance). A plan passes when its moves keep the arm's links clear of every box
(first_collision) and the gripper's own box (the open fingers, or the cup) clear of every box along every
step, the straight descent and rise included (fingers_hit). The usual plan is tried first; if it touches
something, the jobs' plan (a transfer height over the tallest box) with the fingers turned (a cube is held
across either pair of faces; on empty board any heading does), else it is refused naming what is in the way.
Nothing moves before a plan passes.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from armlab.devices.arm import JointTrajectory
from armlab.errors import PLAN_REFUSALS
from armlab.motion import TrajectoryStep
from armlab.motion.clearance import OBJECT_BOX_RADIUS_M, ObstacleBox, box_around, fingers_hit, first_collision
from armlab.motion.safety import UnsafeTrajectory
from armlab.skills.manipulate import TALL_OVER_TARGET_M, plan_pick, plan_pick_steps, plan_place, plan_place_steps
from armlab.station.core import Station

SAME_OBJECT_M = 0.02  # a detection this close (x-y) to the grabbed block or the drop's support is that object
ON_TOP_TOL_M = 0.01  # a target point this close to a detection's top (or above it), over it, is on it
FREE_YAWS_RAD = (0.0, math.pi / 2, math.pi / 4, -math.pi / 4)  # finger headings tried where any will do
WRIST_OFFSETS_RAD = (0.0, math.pi / 2, -math.pi / 2)  # IK seeds of the usual plan: the fingers as they come, turned a quarter
OVER_TARGET_M = 0.01  # a step whose gripper point stays this close (x-y) to the target is the straight descent or rise


def known_obstacles(station: Station, target_m, *exclude_xy_m) -> list[ObstacleBox]:
    """A box around every detected block or stack (top = its measured top), except those at exclude_xy_m and
    the one the target point stands on (a click on a block's edge grabs or drops on that block)."""
    target = np.asarray(target_m, float)
    boxes = []
    for detection in station.detections().blocks:
        position = detection.position_m
        if any(math.dist(position[:2], xy[:2]) < SAME_OBJECT_M for xy in exclude_xy_m):
            continue
        if np.all(np.abs(target[:2] - np.asarray(position[:2])) < OBJECT_BOX_RADIUS_M) and target[2] >= position[2] - ON_TOP_TOL_M:
            continue
        name = f"the {detection.color or 'unknown'} block at ({position[0] * 1000:.0f}, {position[1] * 1000:.0f}) mm"
        boxes.append(box_around(name, position[:2], OBJECT_BOX_RADIUS_M, float(position[2])))
    return boxes


def path_problem(station: Station, steps: list, boxes: list[ObstacleBox], held_edge_m: float | None, target_m) -> str | None:
    """What in `boxes` the plan's moves would touch (links or the gripper's box), None when it clears them all.
    Where the gripper is over the target (the end of the transfer, the straight descent and rise) its own box is
    what is checked (and the links against a column towering over the target, as the jobs do): the links'
    inflated points around the finger tips would refuse any neighbour closer than a block and a half."""
    fingers = station.finger_box()  # the gripper's own box, checked exactly: the link points stop at the gripper point
    target = np.asarray(target_m, float)
    tall = [box for box in boxes if box.top_z_m > target[2] + TALL_OVER_TARGET_M]
    for step in steps:
        if not isinstance(step, TrajectoryStep):
            continue
        trajectory = step.trajectory
        points = np.asarray(station.model.fk(trajectory.positions_rad), float).reshape(-1, 4, 4)[:, :2, 3]
        over = np.linalg.norm(points - target[:2], axis=1) <= OVER_TARGET_M  # samples with the gripper over the target
        problem = None
        for mask, link_boxes in ((over, tall), (~over, boxes)):
            if mask.sum() >= 2 and problem is None:
                part = JointTrajectory(trajectory.times_s[mask] - trajectory.times_s[mask][0], trajectory.positions_rad[mask])
                problem = first_collision(station.model, part, link_boxes, held_edge_m=held_edge_m,
                                          gripper_checked_m=fingers.back_m)
        problem = problem or fingers_hit(station.model, trajectory, fingers, boxes)
        if problem is not None:
            return f"{step.name}: {problem}"
    return None


def _first_clear(station: Station, what: str, usual: Callable[[float], list], around: Callable[[float | None], list],
                 yaws: tuple, boxes: list[ObstacleBox], held_edge_m: float | None, target_m) -> list:
    """The first plan that clears `boxes`: the usual one with the fingers as IK turns them, then across the other
    faces (the wrist seeded a quarter turn over), then the jobs' (transfer height over the tallest box) at each
    heading; UnsafeTrajectory naming what is in the way when none does."""
    refusals, problems = [], []
    for plan, options in ((usual, WRIST_OFFSETS_RAD), (around, yaws)):
        for option in options:
            try:
                steps = plan(option)
            except PLAN_REFUSALS as error:
                refusals.append(error)
                continue
            problem = path_problem(station, steps, boxes, held_edge_m, target_m)
            if problem is None:
                return steps
            problems.append(problem)
    if not problems:  # no plan at all (out of reach, a joint limit): the planner's own reason, as without obstacles
        raise refusals[0]
    raise UnsafeTrajectory(f"{what}: no path clears the blocks the station sees ({problems[0]}); move them or choose another spot")


def _yaws(yaw_rad: float | None) -> tuple:
    """The finger headings to try: a block's yaw and the quarter turn (a cube either way), else any."""
    return (None, *FREE_YAWS_RAD) if yaw_rad is None else (yaw_rad, yaw_rad + math.pi / 2)


def plan_clear_pick(station: Station, top_m, yaw_rad: float | None, edge_m: float, boxes: list[ObstacleBox]) -> list:
    """The pick of the block (or empty-board point) whose top centre is top_m, clear of `boxes`."""
    top = np.asarray(top_m, float)
    return _first_clear(station, f"grab at ({top[0] * 1000:.0f}, {top[1] * 1000:.0f}) mm",
                        lambda offset: plan_pick_steps(station, top, yaw_rad, wrist_offset_rad=offset), lambda yaw: plan_pick(station, top, yaw, edge_m, boxes),
                        _yaws(yaw_rad), boxes, None, top)


def plan_clear_place(station: Station, surface_m, yaw_rad: float | None, edge_m: float, boxes: list[ObstacleBox]) -> list:
    """The place of the held block (edge edge_m) on surface_m, clear of `boxes`."""
    surface = np.asarray(surface_m, float)
    return _first_clear(station, f"drop at ({surface[0] * 1000:.0f}, {surface[1] * 1000:.0f}) mm",
                        lambda offset: plan_place_steps(station, surface, yaw_rad, edge_m, wrist_offset_rad=offset),
                        lambda yaw: plan_place(station, surface, yaw, edge_m, boxes), _yaws(yaw_rad), boxes, edge_m, surface)
