"""sort_by_tag (the UR3 write-up): every block whose top carries an ArUco id goes to the place its id
names (workcell config: block_tags → places_m), stacked there when several blocks share an id
(large ones first). A tag too small to read goes by its block's colour when exactly one configured id has
that colour (perception sets the destination, armlab.vision.blocks). A block whose id has no destination in the workcell config stays where it is, and
the job fails once the others are sorted, naming that block (UnknownTagDestination)."""

from __future__ import annotations

from armlab.errors import InvalidInput
from armlab.scene import as_workcell
from armlab.tasks.columns import Column, unseen_as_none
from armlab.tasks.look_poses import seeing_look_pose
from armlab.tasks.policy import Move, Plan, cubes
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block


class UnknownTagDestination(InvalidInput):
    """sort_by_tag met blocks whose ArUco id names no place in the workcell config (block_tags.ids)."""


def _describe(block: Block) -> str:
    x, y = block.position_m[0] * 1000, block.position_m[1] * 1000
    return f"id {block.aruco_id} on the {block.color or ''} {block.size or ''} block at ({x:.0f}, {y:.0f}) mm".replace("  ", " ")


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    workcell = as_workcell(getattr(runner.station.config, "workcell", None))  # the station's
    columns = {int(dest): Column(f"place {dest}", tuple(map(float, xy))) for dest, xy in workcell.places_m.items()}
    runner.reserved_m.extend(column.base_xy_m for column in columns.values())
    runner.look_pose_rad = seeing_look_pose(runner.station)  # the RX200's sleep pose hides blocks near (0, 130) mm

    def policy(objects: list[Seen], given_up: set) -> Plan:
        for column in columns.values():
            column.observe(objects, unseen_as_none(runner))
            if column.stand_in() is not None:  # an obstacle for the moves planned from this look
                objects.append(column.stand_in())
        tops = {id(c.top) for c in columns.values() if c.top is not None}
        tagged = [b for b in cubes(objects) if b.destination in columns and id(b) not in tops]
        unknown = [b for b in cubes(objects) if b.aruco_id is not None and b.destination not in columns]
        moves = []
        for block in sorted(tagged, key=lambda b: (-b.stack_level, b.size != "large")):
            column = columns[block.destination]
            yaw = column.top.yaw_rad if column.top is not None else 0.0
            tag = f"id {block.aruco_id}" if block.aruco_id is not None else f"unread tag, {block.color}"
            moves.append(Move(block, column.surface_m(), f"{tag} → place {block.destination}", yaw_rad=yaw,
                              on_placed=lambda edge, c=column, b=block: c.add(b, edge)))
        for block in unknown:
            runner.note_once(f"block with {_describe(block)}: no destination for that id in the workcell config")
        if not tagged and unknown:  # everything it can sort is sorted: fail, naming what it had to leave
            known = ", ".join(str(i) for i in sorted(workcell.block_tags.ids))
            raise UnknownTagDestination(
                f"no destination for {'; '.join(_describe(b) for b in unknown)}: the workcell "
                f"'{workcell.name}' maps only ids {known} to places (block_tags.ids); the block stays where it is")
        done = sum(column.height for column in columns.values())
        return Plan(moves, done=done, left=len(tagged), finished=not tagged)

    return policy
