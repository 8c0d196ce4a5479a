"""clear_table leaves what lies beyond the arm's reach (a hand, pliers at the board's edge: the realistic
camera's clutter) instead of trying to pick it again and again (the fingers would go into the board),
names it once, and finishes when only such things are left."""

from __future__ import annotations

from seen_blocks import seen_block
from test_stack_high_plan import fake_runner

from armlab.tasks import clear_table


def _runner():
    runner = fake_runner()
    runner.station.config = None  # the default workcell (rx200_armlab)
    runner.notes = []
    runner.note_once = lambda reason: reason in runner.notes or runner.notes.append(reason)
    runner.height_at = lambda xy: 0.0  # the depth image measures the bare board everywhere
    return runner


HAND = seen_block("unknown", "large", 0.498, 0.101, 0.031, cube=False)
BLOCK = seen_block("red", "large", 0.10, 0.20, 0.038)


def test_an_object_beyond_reach_is_left_and_named_once():
    runner = _runner()
    policy = clear_table.make_policy(3, {}, runner)
    plan = policy([HAND, BLOCK], set())
    assert [m.block for m in plan.moves] == [BLOCK]
    assert not plan.finished and plan.left == 1
    plan = policy([HAND], set())
    assert plan.finished and not plan.moves
    assert runner.notes == ["left the unknown large object beyond the arm's reach"]
