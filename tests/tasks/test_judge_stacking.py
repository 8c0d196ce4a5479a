"""The competition judge's stacking events (DESIGN §7, armlab/tasks/judge/stacking.py): pick_stack, stack_high
and to_the_sky, on hand-made final states whose scores are worked out by hand here."""

import pytest
from judge_scenes import (
    INSIDE_BOX_PATH_M,
    RAINBOW,
    TAGS_M,
    block,
    edge,
    pile,
    rules_of,
    three_on_tag_2,
    truth,
)

from armlab.tasks.judge import columns, judge

# ---------------------------------------------------------------------------------------------------
# pick_stack


def test_pick_stack_column_on_a_tag_with_gripper_inside_the_box():
    score = judge("pick_stack", 1, truth(three_on_tag_2()), sim_time_s=60.0, gripper_path_m=INSIDE_BOX_PATH_M)
    assert (score.points, score.max_points, score.full) == (3 * 40 + 20, 140, True)
    # Same with the tag layout passed in instead of read from configuration.
    passed = judge("pick_stack", 1, truth(three_on_tag_2()), sim_time_s=60.0, gripper_path_m=INSIDE_BOX_PATH_M,
                   tag_centres_m={1: TAGS_M[0], 2: TAGS_M[1]})
    assert passed.points == 140
    # Tags elsewhere: the same column is off-tag.
    moved = judge("pick_stack", 1, truth(three_on_tag_2()), sim_time_s=60.0, gripper_path_m=INSIDE_BOX_PATH_M,
                  tag_centres_m=[(0.0, 0.0)])
    assert moved.points == 0


def test_pick_stack_bottom_31_mm_from_a_tag_scores_nothing():
    near = judge("pick_stack", 1, truth(three_on_tag_2(dx=-0.029)), sim_time_s=60.0, gripper_path_m=INSIDE_BOX_PATH_M)
    assert near.points == 140
    off = judge("pick_stack", 1, truth(three_on_tag_2(dx=-0.031)), sim_time_s=60.0, gripper_path_m=INSIDE_BOX_PATH_M)
    assert off.points == 0
    assert "31 mm" in rules_of(off, "stacked")[0].detail


def leaning_pile(x, y, lean_x_m, specs):
    """Blocks each set lean_x_m along x from the one below (a column while |lean| <= 15 mm), bottom first."""
    objects, bottom = [], 0.0
    for i, (obj_id, color, size) in enumerate(specs):
        objects.append(block(obj_id, color, size, x + i * lean_x_m, y, bottom + edge(size) / 2.0))
        bottom += edge(size)
    return objects


def test_pick_stack_measures_a_leaning_column_at_its_bottom_block():
    """The rule is the column's bottom within 30 mm of a tag centre; a leaning pile's top is elsewhere.
    Tag 2 at (250, -25) mm; blocks 14 mm apart along x."""
    three = [("a", "red", "large"), ("b", "green", "large"), ("c", "blue", "large")]
    # bottom 10 mm from the tag, leaning away: top 38 mm from it -> on the tag
    away = judge("pick_stack", 1, truth(leaning_pile(0.240, -0.025, -0.014, three)), sim_time_s=60.0,
                 gripper_path_m=INSIDE_BOX_PATH_M)
    assert [len(c) for c in columns(truth(leaning_pile(0.240, -0.025, -0.014, three))["objects"])] == [3]
    assert (away.points, away.full) == (3 * 40 + 20, True)
    # bottom 35 mm from the tag, leaning back over it: top 7 mm from it -> off the tag, "35 mm" said
    back = judge("pick_stack", 1, truth(leaning_pile(0.215, -0.025, 0.014, three)), sim_time_s=60.0,
                 gripper_path_m=INSIDE_BOX_PATH_M)
    assert back.points == 0
    assert all("35 mm" in rule.detail for rule in rules_of(back, "stacked"))


def test_pick_stack_needs_three_in_the_column_and_scores_only_upright_ones():
    two = pile(-0.25, 0.275, [("a", "red", "large"), ("b", "green", "large")])
    score = judge("pick_stack", 1, truth(two, block("c", "blue", "large", 0.0, 0.1)), sim_time_s=60.0,
                  gripper_path_m=INSIDE_BOX_PATH_M)
    assert score.points == 0
    # Top block tipped 20°: the column still has three, the tipped block scores nothing, no bonus.
    score = judge("pick_stack", 1, truth(three_on_tag_2(tilts={2: 20.0})), sim_time_s=60.0,
                  gripper_path_m=INSIDE_BOX_PATH_M)
    assert score.points == 2 * 40


def test_pick_stack_level_2_mixed_sizes_on_two_tags():
    first = pile(-0.25, -0.025, [("l1", "red", "large"), ("l2", "red", "large"), ("s1", "blue", "small")])
    second = pile(0.25, 0.275, [("l3", "green", "large"), ("s2", "green", "small"), ("s3", "blue", "small")])
    score = judge("pick_stack", 2, truth(first, second), sim_time_s=119.0, gripper_path_m=INSIDE_BOX_PATH_M)
    assert (score.points, score.max_points, score.full) == (6 * 40 + 40, 280, True)


def test_pick_stack_bonus_lost_when_the_gripper_leaves_the_box_or_path_is_missing():
    for sample in ([0.261, 0.1, 0.1], [0.0, -0.036, 0.1], [0.0, 0.286, 0.1], [0.0, 0.1, 0.301]):
        path = [*INSIDE_BOX_PATH_M, sample, [0.0, 0.1, 0.1]]
        score = judge("pick_stack", 1, truth(three_on_tag_2()), sim_time_s=60.0, gripper_path_m=path)
        assert (score.points, score.full) == (120, False), sample
        assert "left the box" in rules_of(score, "bonus")[0].detail
    unrecorded = judge("pick_stack", 1, truth(three_on_tag_2()), sim_time_s=60.0)
    assert unrecorded.points == 120
    assert "not recorded" in rules_of(unrecorded, "bonus")[0].detail


# ---------------------------------------------------------------------------------------------------
# stack_high


def test_stack_high_column_points_and_rainbow_bonus():
    column = pile(0.1, 0.2, [(f"b{i}", color, "large") for i, color in enumerate(RAINBOW)])
    score = judge("stack_high", 1, truth(column), sim_time_s=500.0)
    assert (score.points, score.max_points, score.full) == (10 + 20 + 30 + 40 + 50 + 60 + 40, 250, True)
    wrong = pile(0.1, 0.2, [(f"b{i}", color, "large") for i, color in enumerate(["orange", "red", *RAINBOW[2:]])])
    assert judge("stack_high", 1, truth(wrong), sim_time_s=500.0).points == 210
    two = pile(0.1, 0.2, [(f"b{i}", c, "large") for i, c in enumerate(RAINBOW[:3])]) + pile(
        -0.1, 0.2, [(f"c{i}", c, "large") for i, c in enumerate(RAINBOW[3:])])
    assert judge("stack_high", 1, truth(two), sim_time_s=500.0).points == 2 * (10 + 20 + 30)


def test_stack_high_fallen_and_tipped_blocks_break_columns():
    # Five stacked, violet lying unsupported 60 mm up (fell against something): 10+20+30+40+50.
    five = pile(0.1, 0.2, [(f"b{i}", c, "large") for i, c in enumerate(RAINBOW[:5])])
    fallen = block("v", "violet", "large", -0.2, 0.2, z=0.06)
    assert judge("stack_high", 1, truth(five, fallen), sim_time_s=1.0).points == 150
    # Four stacked with the third tipped 20°: the column is two (10+20); two singles elsewhere 10 each.
    four = pile(0.1, 0.2, [(f"b{i}", c, "large") for i, c in enumerate(RAINBOW[:4])], tilts={2: 20.0})
    singles = [block("b4", "blue", "large", -0.2, 0.2), block("b5", "violet", "large", -0.1, 0.3)]
    assert judge("stack_high", 1, truth(four, singles), sim_time_s=1.0).points == 30 + 20


def test_stack_high_level_2_sizes_do_not_mix():
    large = pile(0.1, 0.2, [(f"L{i}", c, "large") for i, c in enumerate(RAINBOW)])
    small = pile(-0.1, 0.2, [(f"S{i}", c, "small") for i, c in enumerate(RAINBOW)])
    assert judge("stack_high", 2, truth(large, small), sim_time_s=1.0).points == 500
    # The small stack moved onto the large one: it rests on a large block, so it forms no small column.
    on_top = pile(0.1, 0.2, [(f"L{i}", c, "large") for i, c in enumerate(RAINBOW)]
                  + [(f"S{i}", c, "small") for i, c in enumerate(RAINBOW)])
    assert judge("stack_high", 2, truth(on_top), sim_time_s=1.0).points == 250


# ---------------------------------------------------------------------------------------------------
# to_the_sky


def test_to_the_sky_tallest_tower_of_10_scores_8x30_plus_2x50():
    tower = pile(0.0, 0.25, [(f"t{i}", RAINBOW[i % 6], "large") for i in range(10)])
    short = pile(0.2, 0.2, [(f"s{i}", "red", "large") for i in range(2)])
    score = judge("to_the_sky", 1, truth(tower, short), sim_time_s=590.0)
    assert score.points == 8 * 30 + 2 * 50
    assert score.max_points == 8 * 30 + 4 * 50  # 12 large blocks in truth
    fed = judge("to_the_sky", 1, truth(tower), sim_time_s=590.0, blocks_available=15)
    assert (fed.points, fed.max_points, fed.full) == (340, 8 * 30 + 7 * 50, False)
    alone = judge("to_the_sky", 1, truth(tower), sim_time_s=590.0)
    assert (alone.max_points, alone.full) == (340, True)
    # The seventh block tipped: the upright tower is six high.
    tipped = pile(0.0, 0.25, [(f"t{i}", RAINBOW[i % 6], "large") for i in range(10)], tilts={6: 20.0})
    assert judge("to_the_sky", 1, truth(tipped), sim_time_s=1.0).points == 6 * 30
    with pytest.raises(ValueError, match="blocks_available"):
        judge("to_the_sky", 1, truth(tower), sim_time_s=1.0, blocks_available=9)
