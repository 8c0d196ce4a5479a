"""The competition judge's sorting events (DESIGN §7, armlab/tasks/judge/sorting.py): pick_sort and sort_stack,
on hand-made final states whose scores are worked out by hand here."""

from judge_scenes import (
    RAINBOW,
    block,
    distractor,
    pile,
    quat_tilt,
    rules_of,
    sorted_six,
    truth,
)

from armlab.scene import generate_scene
from armlab.tasks.judge import judge

# ---------------------------------------------------------------------------------------------------
# pick_sort


def test_pick_sort_sides_and_level_bonus():
    score = judge("pick_sort", 2, truth(sorted_six()), sim_time_s=100.0)
    assert (score.points, score.max_points, score.within_limit, score.full) == (6 * 30 + 20, 200, True, True)
    # Wrong sides: a small block at x > 0, a large block at x < 0, a large block at y > 0.
    objects = sorted_six()
    objects[3]["position_m"][0] = 0.10  # small, x > 0
    objects[0]["position_m"][0] = -0.30  # large, x < 0
    objects[1]["position_m"][1] = 0.05  # large, y > 0
    score = judge("pick_sort", 2, truth(objects), sim_time_s=100.0)
    assert score.points == 3 * 30  # no bonus
    assert not score.full
    assert {r.object_ids[0]: r.points for r in rules_of(score, "sorted")} == {
        "L1": 0, "L2": 0, "L3": 30, "S1": 0, "S2": 30, "S3": 30}
    assert rules_of(score, "bonus")[0].points == 0


def test_pick_sort_tipped_block_scores_nothing_and_costs_the_bonus():
    objects = sorted_six()
    objects[2]["quat_wxyz"] = quat_tilt(20.0, (0.0, 1.0, 0.0))
    score = judge("pick_sort", 2, truth(objects), sim_time_s=100.0)
    assert score.points == 5 * 30
    assert "tipped 20" in [r for r in score.breakdown if r.object_ids == ("L3",)][0].detail


def test_time_over_the_limit_loses_only_the_bonus():
    at_limit = judge("pick_sort", 2, truth(sorted_six()), sim_time_s=180.0)
    assert (at_limit.points, at_limit.within_limit, at_limit.full) == (200, True, True)
    over = judge("pick_sort", 2, truth(sorted_six()), sim_time_s=180.5)
    assert (over.points, over.max_points, over.within_limit, over.full) == (180, 200, False, False)
    assert "limit" in rules_of(over, "bonus")[0].detail
    # A non-bonus event keeps its points but is not "full" when late.
    line = [block(f"b{i}", color, "large", -0.125 + 0.05 * i, 0.2) for i, color in enumerate(RAINBOW)]
    late = judge("line_up", 1, truth(line), sim_time_s=601.0)
    assert (late.points, late.max_points, late.within_limit, late.full) == (200, 200, False, False)


def test_generated_pick_sort_start_scores_nothing():
    for level, n_blocks in ((1, 3), (2, 6), (3, 9)):
        scene = generate_scene("pick_sort", level, seed=5)
        score = judge("pick_sort", level, scene.to_dict(), sim_time_s=0.0)
        assert score.points == 0, score.breakdown
        assert score.max_points == 30 * n_blocks + 10 * level
        assert not score.full


# ---------------------------------------------------------------------------------------------------
# sort_stack


def test_sort_stack_level_1_sides_and_bonus():
    objects = [block("r", "red", "large", 0.1, -0.1), block("g", "green", "large", 0.2, -0.1),
               block("b", "blue", "large", 0.15, -0.05)]
    score = judge("sort_stack", 1, truth(objects), sim_time_s=150.0)
    assert (score.points, score.max_points, score.full) == (3 * 30 + 10, 100, True)
    objects[2]["position_m"][1] = 0.05
    assert judge("sort_stack", 1, truth(objects), sim_time_s=150.0).points == 60


def sort_stack_columns(large_colors, small_colors):
    return (pile(0.15, -0.1, [(f"L{i}", c, "large") for i, c in enumerate(large_colors)])
            + pile(-0.15, -0.1, [(f"S{i}", c, "small") for i, c in enumerate(small_colors)]))


def test_sort_stack_level_2_column_order_with_ties_either_way():
    # Large red, blue, blue: red must be 1st, the blues 2nd and 3rd either way; small yellow then two greens.
    score = judge("sort_stack", 2, truth(sort_stack_columns(["red", "blue", "blue"], ["yellow", "green", "green"])),
                  sim_time_s=170.0)
    assert (score.points, score.max_points, score.full) == (6 * 30 + 20, 200, True)
    # Blue at the bottom: red (wants 1st) at 2nd and the lower blue (wants 2nd-3rd) at 1st score nothing.
    wrong = judge("sort_stack", 2, truth(sort_stack_columns(["blue", "red", "blue"], ["yellow", "green", "green"])),
                  sim_time_s=170.0)
    assert wrong.points == 30 + 3 * 30
    assert {r.object_ids[0]: r.points for r in rules_of(wrong, "sorted")} == {
        "L0": 0, "L1": 0, "L2": 30, "S0": 30, "S1": 30, "S2": 30}


def test_sort_stack_level_2_blocks_outside_the_sides_single_column():
    # Large red+blue stacked, the other blue alone on the same side: it is not in the side's (tallest) column.
    large = pile(0.15, -0.1, [("L0", "red", "large"), ("L1", "blue", "large")])
    lone = block("L2", "blue", "large", 0.25, -0.05)
    small = pile(-0.15, -0.1, [("S0", "red", "small"), ("S1", "orange", "small"), ("S2", "violet", "small")])
    score = judge("sort_stack", 2, truth(large, lone, small), sim_time_s=170.0)
    assert score.points == 2 * 30 + 3 * 30
    # A small block on the large side, even in order, is not on its side.
    small_wrong = pile(0.15, -0.1, [("L0", "red", "large"), ("L1", "blue", "large"), ("L2", "blue", "large"),
                                    ("S0", "red", "small")])
    rest = pile(-0.15, -0.1, [("S1", "orange", "small"), ("S2", "violet", "small")])
    assert judge("sort_stack", 2, truth(small_wrong, rest), sim_time_s=170.0).points == 3 * 30


def test_sort_stack_level_3_distractor_at_negative_y_loses_90():
    blocks = sort_stack_columns(["green", "green", "green"], ["red", "orange", "yellow"])
    score = judge("sort_stack", 3, truth(blocks, distractor("d1", 0.0, 0.2), distractor("d2", -0.3, 0.3, "arch")),
                  sim_time_s=100.0)
    assert (score.points, score.max_points, score.full) == (6 * 30 + 30 + 90, 300, True)
    stray = judge("sort_stack", 3, truth(blocks, distractor("d1", 0.0, -0.01), distractor("d2", -0.3, 0.3)),
                  sim_time_s=100.0)
    assert stray.points == 6 * 30 + 30
    assert rules_of(stray, "distractors")[0].object_ids == ("d1",)
    # Late: the level bonus goes, the distractor points stay.
    late = judge("sort_stack", 3, truth(blocks, distractor("d1", 0.0, 0.2)), sim_time_s=181.0)
    assert (late.points, late.within_limit, late.full) == (6 * 30 + 90, False, False)
