"""A job never fails for want of a free spot (issue 19 item 5). When the region a job puts blocks aside in
is full, the block goes to a free spot elsewhere in the arm's reach; when the whole board is full, the
job leaves that block where it is with the reason and goes on with the moves it has. Before, free_spot's
RuntimeError escaped the policy and failed the job at its first look. Plan level, no simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from seen_blocks import seen_block
from test_stack_high_plan import fake_runner

from armlab.tasks import sort_stack, stack_high, to_the_sky
from armlab.tasks.runner import TaskRunner

LARGE_EDGE_M = 0.038


def runner_with_free_spot():
    """fake_runner with TaskRunner's own free_spot, a flat measured board, and the reasons it gives."""
    runner = fake_runner()
    runner.failures = []
    runner.free_spot = lambda *a, **k: TaskRunner.free_spot(runner, *a, **k)
    runner.free_spot_in_reach = lambda *a, **k: TaskRunner.free_spot_in_reach(runner, *a, **k)
    runner.edge_of = lambda block: runner.edges_m.get(block.size or "large")
    runner.height_at = lambda xy: 0.0
    runner.note_once = lambda reason: runner.failures.append(reason) if reason not in runner.failures else None
    return runner


def crowd(y_min_m: float) -> list:
    """Distractors every 50 mm over the board from y_min_m up: no spot there is a block's width free."""
    return [seen_block(None, None, float(x), float(y), 0.03, cube=False)
            for x in np.arange(-0.45, 0.451, 0.05) for y in np.arange(y_min_m, 0.451, 0.05)]


# A small violet on a small block: it must go aside to uncover it.
PILE = seen_block("violet", "small", 0.0, 0.25, 0.05, level=2, stack_sizes=("small", "small"))


def test_a_pile_top_goes_aside_outside_a_full_aside_region():
    runner = runner_with_free_spot()
    objects = [PILE, *[o for o in crowd(0.05) if math.dist(o.position_m[:2], PILE.position_m[:2]) > 0.03]]
    plan = sort_stack.make_policy(2, {}, runner)(objects, set())
    uncover = [m for m in plan.moves if m.block is PILE]
    assert uncover and uncover[0].why == "uncover the pile under it", plan.moves
    spot = uncover[0].to_m[:2]
    assert min(math.dist(spot, o.position_m[:2]) for o in objects if o is not PILE) >= LARGE_EDGE_M / 2 + 0.019
    assert 0.14 <= math.hypot(*spot) <= 0.34


def test_a_full_board_leaves_the_pile_with_a_reason_and_the_job_goes_on():
    runner = runner_with_free_spot()
    objects = [PILE, *[o for o in crowd(-0.15) if math.dist(o.position_m[:2], PILE.position_m[:2]) > 0.03]]
    plan = sort_stack.make_policy(2, {}, runner)(objects, set())
    assert not [m for m in plan.moves if m.block is PILE]
    assert any("no free spot" in reason for reason in runner.failures), runner.failures


def test_to_the_sky_turns_no_block_when_the_board_is_full():
    runner = runner_with_free_spot()
    tipped = seen_block("red", "large", 0.1, 0.2, 0.038, yaw_rad=0.7)  # not facing the arm: it would be set down turned, on a free spot
    objects = [tipped, *[o for o in crowd(-0.15) if math.dist(o.position_m[:2], tipped.position_m[:2]) > 0.03]]
    assert to_the_sky.turn_moves(runner, [tipped], objects) == []
    assert any("no free spot" in reason for reason in runner.failures), runner.failures


def test_stack_high_with_no_spot_for_its_columns_says_why():
    """Truly impossible (no column spot the camera sees whole): the job fails with the reason, not a TypeError."""
    runner = fake_runner()
    runner.in_view = lambda xy, height_m, margin_px=40.0: False
    with pytest.raises(RuntimeError, match="no place for the columns"):
        stack_high.choose_bases(runner, [], ["large", "small"])
