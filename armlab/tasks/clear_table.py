"""clear_table (the Sawyer project): every object the camera finds on the board — blocks of any
colour and size, distractors of any shape — into the bin area of the workcell config; blocks may be
stacked there when the bin's floor is full."""

from __future__ import annotations

import math

import numpy as np

from armlab.scene import as_workcell
from armlab.tasks.look_poses import seeing_look_pose
from armlab.tasks.policy import Move, Plan, near
from armlab.tasks.runner import TaskRunner
from armlab.tasks.seen import Seen, is_unseen

SPOT_PITCH_M = 0.045
SPOT_EMPTY_HEIGHT_M = 0.010  # a floor spot whose measured height is above this holds something
BEYOND_REACH_MARGIN_M = 0.05  # past the workcell's scene reach by this much: nothing the arm can clear (a hand, tools at the board's edge)


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    workcell = as_workcell(getattr(runner.station.config, "workcell", None))  # the station's
    bin_ = workcell.bin
    reach_m = workcell.scene.reach_m[1] + BEYOND_REACH_MARGIN_M
    runner.look_pose_rad = seeing_look_pose(runner.station)  # every object must be seen: the sleep pose hides those near (0, 140) mm
    xs = np.arange(bin_.x_range_m[0] + 0.025, bin_.x_range_m[1] - 0.02 + 1e-9, SPOT_PITCH_M)
    ys = np.arange(bin_.y_range_m[0] + 0.025, bin_.y_range_m[1] - 0.02 + 1e-9, SPOT_PITCH_M)
    spots = [(float(x), float(y)) for y in ys for x in xs if 0.14 <= math.hypot(x, y) <= 0.36]

    def policy(objects: list[Seen], given_up: set) -> Plan:
        inside = [o for o in objects if bin_.contains(*o.position_m[:2])]
        outside = [o for o in objects if not bin_.contains(*o.position_m[:2]) and not is_unseen(o)]
        for obj in [o for o in outside if math.hypot(*o.position_m[:2]) > reach_m]:
            runner.note_once(f"left the {_kind(obj)} beyond the arm's reach")
        outside = [o for o in outside if math.hypot(*o.position_m[:2]) <= reach_m]
        # Free: no detection near and nothing measured standing there (what the job put in the bin can go unseen).
        free = [s for s in spots if not any(near(o.position_m, s, 0.035) for o in inside) and runner.height_at(s) <= SPOT_EMPTY_HEIGHT_M]
        bases = sorted((o for o in inside if o.is_cube), key=lambda o: o.position_m[2])
        distractors_out = sum(not o.is_cube and Move(o, (0.0, 0.0, 0.0), "").key() not in given_up for o in outside)
        moves = []
        # Nothing stacks on a distractor nor a distractor on anything: distractors go first, onto the floor, and a
        # block goes on the lowest block in the bin only when the floor has no spot to spare (a column in the bin
        # keeps the arm from the floor spots beside it). Then pile tops first: they uncover blocks.
        for obj in sorted(outside, key=lambda o: (o.is_cube, -o.stack_level)):
            cube = obj.is_cube
            if free and (not cube or len(free) > distractors_out or not bases):
                target = (*free[0], 0.0)
            elif cube and bases:
                target = tuple(float(v) for v in bases[0].position_m)
            else:
                continue
            moves.append(Move(obj, target, f"{_kind(obj)} into the bin", yaw_rad=None))
        hidden = sum(o.stack_level - 1 for o in outside)
        return Plan(moves, done=len(inside), left=len(outside) + hidden, finished=not outside)

    return policy


def _kind(obj: Seen) -> str:
    """'red large block', 'unknown large object': how the job names what it moves or leaves."""
    kind = f"{obj.color or ''} {obj.size or ''} {'block' if obj.is_cube else 'object'}"
    return " ".join(kind.split())
