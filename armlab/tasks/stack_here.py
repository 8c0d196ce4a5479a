"""stack_here: all blocks (or those of one colour and/or size) stacked at a given point, large ones
first. Parameters: x_m, y_m (default: the workcell's sort_by_tag place nearest the arm), color, size."""

from __future__ import annotations

from armlab.scene import as_workcell
from armlab.tasks.columns import Column, unseen_as_none
from armlab.tasks.look_poses import seeing_look_pose
from armlab.tasks.policy import Move, Plan, cubes
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    workcell = as_workcell(getattr(runner.station.config, "workcell", None))  # the station's
    default = min(workcell.places_m.values(), key=lambda xy: xy[0] ** 2 + xy[1] ** 2)
    column = Column("stack", (float(params.get("x_m", default[0])), float(params.get("y_m", default[1]))))
    runner.reserved_m.append(column.base_xy_m)
    runner.look_pose_rad = seeing_look_pose(runner.station)  # the RX200's sleep pose hides blocks near (0, 130) mm

    def wanted(block: Block) -> bool:
        return params.get("color") in (None, block.color) and params.get("size") in (None, block.size)

    def policy(objects: list[Seen], given_up: set) -> Plan:
        column.observe(objects, unseen_as_none(runner))
        if column.stand_in() is not None:  # an obstacle for the moves planned from this look
            objects.append(column.stand_in())
        loose = [b for b in cubes(objects) if wanted(b) and not column.holds(b)]
        larges_left = any(b.size == "large" for b in loose)
        moves = []
        for block in sorted(loose, key=lambda b: (b.size != "large", -b.stack_level)):
            if block.size == "small" and larges_left and block.stack_level == 1:
                continue  # small blocks on top, once every large one is in
            yaw = column.top.yaw_rad if column.top is not None else 0.0
            moves.append(Move(block, column.surface_m(), f"onto the stack at ({column.base_xy_m[0] * 1000:.0f}, "
                              f"{column.base_xy_m[1] * 1000:.0f}) mm", yaw_rad=yaw, on_placed=lambda edge, b=block: column.add(b, edge)))
        return Plan(moves, done=column.height, left=len(loose), finished=not loose)

    return policy
