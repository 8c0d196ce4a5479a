"""pick_stack (DESIGN §7): every block into a column of three or more standing on a calibration tag,
with the gripper kept inside the box over the tag rectangle.

Two columns (large, small) on the two tags nearest the arm when each size has three or more blocks;
otherwise one column, large blocks first. Pile sizes come from the measured piles (stack_sizes), so
hidden blocks are counted before they are seen. The arm looks from the overhead pose (it hides no
block), every planned motion keeps the gripper point inside the judge's box less a margin, and each
column stands a little inside its tag (still well within the judge's 30 mm) so that placing on it
keeps that margin too.
"""

from __future__ import annotations

import math

from armlab.motion.gripper_box import GripperBox
from armlab.tasks.columns import Column
from armlab.tasks.judge import GRIPPER_BOX_M, TAG_RADIUS_M
from armlab.tasks.look_poses import seeing_look_pose
from armlab.tasks.policy import Move, Plan, cubes
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen
from armlab.vision.block import Block

MIN_COLUMN = 3
BOX_MARGIN_M = 0.010  # planned gripper paths keep this far inside the judge's box (tracking error)
GRIPPER_CEILING_M = GRIPPER_BOX_M["z_max"] - 2 * BOX_MARGIN_M  # transfer height limit, under the box's ceiling
BESIDE_COLUMN_M = 0.10  # a block closer than this to a column base is moved before the column grows
COLUMN_INSET_M = 0.012  # a column's base this far (in x and in y) from its tag centre toward the box's middle


def planning_box() -> GripperBox:
    """The judge's gripper box (DESIGN §7) shrunk by BOX_MARGIN_M: where planned gripper paths stay."""
    box = GRIPPER_BOX_M
    judge_box = GripperBox((-box["x_abs_max"], box["y_min"], -1.0), (box["x_abs_max"], box["y_max"], box["z_max"]))
    return judge_box.shrunk(BOX_MARGIN_M)


def column_base(tag_xy, box: GripperBox) -> tuple[float, float]:
    """Where a column on the tag at tag_xy stands: COLUMN_INSET_M toward the box's middle in x and y, so
    a gripper over it stays inside `box` while its bottom block stays within TAG_RADIUS_M of the tag."""
    middle = [(lo + hi) / 2 for lo, hi in zip(box.min_m[:2], box.max_m[:2])]
    base = tuple(float(v + math.copysign(COLUMN_INSET_M, m - v)) for v, m in zip(tag_xy, middle))
    if math.dist(base, tag_xy) > 0.6 * TAG_RADIUS_M:  # the rest of the judge's radius is left for placement error
        raise ValueError(f"COLUMN_INSET_M {COLUMN_INSET_M} m puts a column too far from its tag")
    return base


def pile_sizes(block: Block) -> list[str]:
    """Sizes of the pile whose top is `block`, bottom-up (the top's own size when not measured)."""
    return list(block.stack_sizes) or [block.size] * int(block.stack_level)


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    runner.max_transfer_z_m = GRIPPER_CEILING_M
    runner.gripper_box = planning_box()
    runner.look_pose_rad = seeing_look_pose(runner.station)
    tags = sorted(runner.tag_centres(), key=lambda xy: (math.hypot(*xy), xy[0]))
    large = Column("large column", column_base(tags[0], runner.gripper_box))
    small = Column("small column", column_base(tags[1], runner.gripper_box))
    runner.reserved_m = [large.base_xy_m, small.base_xy_m]

    def policy(objects: list[Seen], given_up: set) -> Plan:
        large.observe(objects, runner.height_at)
        small.observe(objects, runner.height_at)
        blocks = cubes(objects)
        in_columns = {id(c.top) for c in (large, small) if c.top is not None}
        loose = [b for b in blocks if id(b) not in in_columns]
        # Every block seen or counted under a pile top, and every block already in a column, by size.
        sizes = [s for b in loose for s in pile_sizes(b)] + [p.size for c in (large, small) for p in c.placed]
        two_columns = sizes.count("large") >= MIN_COLUMN and sizes.count("small") >= MIN_COLUMN
        done = large.height + small.height
        left = sum(len(pile_sizes(b)) for b in loose)
        moves = []
        # Blocks beside a column base first (once the column is tall the arm cannot reach down beside
        # it), then pile tops (they uncover blocks), large before small.
        def order(b):
            beside = min(math.dist(b.position_m[:2], c.base_xy_m) for c in (large, small)) < BESIDE_COLUMN_M
            return (not beside, -b.stack_level, b.size != "large")

        for block in sorted(loose, key=order):
            if two_columns:
                column = large if block.size == "large" else small
            else:
                column = large
                large_left = any("large" in pile_sizes(b) for b in loose)
                if block.size == "small" and large_left and block.stack_level == 1:
                    continue  # small blocks go on top once every large one is in
            yaw = column.top.yaw_rad if column.top is not None else 0.0
            moves.append(Move(block, column.surface_m(), f"onto the {column.name}", yaw_rad=yaw,
                              on_placed=lambda edge, c=column, b=block: c.add(b, edge)))
        return Plan(moves, done=done, left=left, finished=not loose)

    return policy
