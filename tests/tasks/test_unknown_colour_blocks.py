"""Blocks of a colour outside the rainbow (perception's 'unknown', or an operator-taught 'pink': issue 17
item 2) in jobs that order blocks by rainbow rank: the plan neither fails on them nor stacks them or lines
them up. Plan level: stack_high L2's idealized board (test_stack_high_plan.PlanWorld), line_up's layout."""

from __future__ import annotations

from dataclasses import replace

import pytest
from test_stack_high_plan import EDGES_M, PlanWorld, fake_runner

from armlab.tasks import line_up, stack_high
from armlab.tasks.runner import TaskRunner

SEED = 3  # an L2 scene whose plan builds both columns


@pytest.mark.parametrize("name", ["unknown", "pink"])
def test_stack_high_leaves_a_block_of_another_colour_out_of_its_columns(name):
    runner = fake_runner()
    world = PlanWorld(SEED, runner)
    odd = next(b for b in world.blocks if b["color"] == "green" and b["size"] == "large")
    odd["color"] = name  # as perception would report it
    runner.height_at = world.height_at
    runner.edge_of = lambda block: EDGES_M[block.size or "large"]
    runner.free_spot = lambda objects, edge_m, **options: TaskRunner.free_spot(runner, objects, edge_m, **options)
    runner.free_spot_in_reach = lambda *args, **options: TaskRunner.free_spot_in_reach(runner, *args, **options)
    policy = stack_high.make_policy(2, {}, runner)
    for _ in range(60):
        plan = policy(world.looks(), set())
        if plan.finished or not plan.moves:
            break
        move = plan.moves[0]
        assert move.block.color != name or "column" not in move.why or "way" in move.why, move.why
        world.move(move.block, move.to_m)
        if move.on_placed is not None:
            move.on_placed(EDGES_M[move.block.size])
    large_pile = max((world.pile_at(b["xy"]) for b in world.blocks if b["size"] == "large" and b["z"] < 1e-6), key=len)
    assert [b["color"] for b in large_pile] == ["red", "orange", "yellow", "blue", "violet"]  # the rest in order, no green
    assert odd["z"] < 1e-6  # the odd block is on the board, not on a column


def test_line_up_puts_no_block_of_another_colour_in_a_slot():
    runner = fake_runner()
    world = PlanWorld(SEED, runner)
    runner.height_at = world.height_at
    runner.edge_of = lambda block: EDGES_M[block.size or "large"]
    runner.free_spot = lambda objects, edge_m, **options: TaskRunner.free_spot(runner, objects, edge_m, **options)
    runner.free_spot_in_reach = lambda *args, **options: TaskRunner.free_spot_in_reach(runner, *args, **options)
    looks = world.looks()
    looks[0] = replace(looks[0], color="unknown")  # as perception would report it
    plan = line_up.make_policy(2, {}, runner)(looks, set())
    assert all(m.block is not looks[0] or "slot" not in m.why for m in plan.moves)
