"""The competition judge (DESIGN §7): hand-made final states whose scores are worked out by hand here, one
group per rule, plus the definitions (upright, on the board, columns, TLS line) and bad input."""

import copy
import json
import math

import numpy as np
import pytest

from armlab.scene import generate_scene
from armlab.tasks.judge import EVENT_LIMITS_S, Score, columns, judge, on_board, tls_line, upright

LARGE_M, SMALL_M = 0.038, 0.025
RAINBOW = ["red", "orange", "yellow", "green", "blue", "violet"]
TAGS_M = [(-0.25, -0.025), (0.25, -0.025), (0.25, 0.275), (-0.25, 0.275)]  # DESIGN §3
INSIDE_BOX_PATH_M = [[0.0, 0.1, 0.25], [0.26, 0.285, 0.30], [-0.26, -0.035, 0.02]]  # box edges are inside


def edge(size):
    return LARGE_M if size == "large" else SMALL_M


def quat_tilt(tilt_deg, axis=(1.0, 0.0, 0.0)):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    half = math.radians(tilt_deg) / 2.0
    return [math.cos(half), *(math.sin(half) * axis)]


def block(obj_id, color, size, x, y, z=None, tilt_deg=0.0, axis=(1.0, 0.0, 0.0)):
    """A block resting on the board at (x, y) unless z (centre) is given."""
    return {"id": obj_id, "type": "block", "color": color, "size": size,
            "position_m": [x, y, edge(size) / 2.0 if z is None else z], "quat_wxyz": quat_tilt(tilt_deg, axis)}


def distractor(obj_id, x, y, kind="cylinder"):
    return {"id": obj_id, "type": kind, "color": "green", "size": None, "position_m": [x, y, 0.019],
            "quat_wxyz": [1.0, 0.0, 0.0, 0.0]}


def pile(x, y, specs, tilts=None):
    """Blocks stacked exactly on one another at (x, y), bottom first; specs are (id, colour, size)."""
    objects, bottom = [], 0.0
    for i, (obj_id, color, size) in enumerate(specs):
        tilt = (tilts or {}).get(i, 0.0)
        objects.append(block(obj_id, color, size, x, y, bottom + edge(size) / 2.0, tilt_deg=tilt))
        bottom += edge(size)
    return objects


def truth(*groups):
    objects = []
    for group in groups:
        objects.extend(group if isinstance(group, list) else [group])
    return {"objects": objects, "sim_time_s": 12.0}


def rules_of(score, name):
    return [rule for rule in score.breakdown if rule.rule == name]


# ---------------------------------------------------------------------------------------------------
# Definitions


def test_upright_within_15_degrees_of_vertical_about_any_axis():
    assert upright(block("a", "red", "large", 0, 0))
    assert upright(block("a", "red", "large", 0, 0, tilt_deg=14.0))
    assert upright(block("a", "red", "large", 0, 0, tilt_deg=14.0, axis=(1.0, 1.0, 0.0)))
    assert not upright(block("a", "red", "large", 0, 0, tilt_deg=16.0, axis=(0.0, 1.0, 0.0)))
    assert not upright(block("a", "red", "large", 0, 0, tilt_deg=20.0, axis=(1.0, -1.0, 0.0)))
    assert not upright(block("a", "red", "large", 0, 0, tilt_deg=180.0))  # upside down
    # Any heading about z is still upright.
    yawed = block("a", "red", "large", 0, 0)
    yawed["quat_wxyz"] = [math.cos(1.2), 0.0, 0.0, math.sin(1.2)]
    assert upright(yawed)


def test_on_board_means_bottom_face_within_6_mm_of_the_surface():
    assert on_board(block("a", "red", "large", 0, 0, z=0.019))
    assert on_board(block("a", "red", "large", 0, 0, z=0.019 + 0.005))
    assert on_board(block("a", "red", "small", 0, 0, z=0.0125 - 0.005))
    assert not on_board(block("a", "red", "large", 0, 0, z=0.019 + 0.007))
    assert not on_board(block("a", "red", "small", 0, 0, z=0.019))  # small block centre at a large one's height
    assert not on_board(block("a", "red", "large", 0, 0, z=0.057))  # on another large block


def test_columns_group_bottom_up_within_15_mm_and_6_mm():
    stack = pile(0.1, 0.1, [("b1", "red", "large"), ("b2", "green", "large"), ("b3", "blue", "small")])
    # Listed top first: columns still come out bottom first.
    found = columns(list(reversed(stack)))
    assert [[b.id for b in col] for col in found] == [["b1", "b2", "b3"]]
    # 14 mm off in xy joins; 16 mm does not.
    near = block("n2", "red", "large", 0.3 + 0.014, 0.0, z=0.057)
    far = block("f2", "red", "large", -0.3 + 0.016, 0.0, z=0.057)
    found = columns([block("n1", "red", "large", 0.3, 0.0), near, block("f1", "red", "large", -0.3, 0.0), far])
    assert sorted([b.id for b in col] for col in found) == [["f1"], ["n1", "n2"]]
    # A block hovering 7 mm above the top, or with nothing below it, is in no column.
    hover = block("h2", "red", "large", 0.0, 0.3, z=0.057 + 0.007)
    fallen = block("x", "blue", "large", 0.2, 0.3, z=0.057)
    found = columns([block("h1", "red", "large", 0.0, 0.3), hover, fallen])
    assert [[b.id for b in col] for col in found] == [["h1"]]


def test_columns_ignore_distractors_and_what_rests_on_them():
    base = distractor("cyl", 0.1, 0.1)  # 38 mm tall, top at 0.038
    on_top = block("b", "red", "large", 0.1, 0.1, z=0.057)
    assert columns([base, on_top]) == []


def test_tls_line_fits_perpendicular_distances():
    # Points on y = 2x + 1: direction (1, 2)/sqrt(5), centroid the mean.
    xs = np.array([-1.0, 0.0, 2.0, 3.0])
    centre, direction = tls_line(np.stack([xs, 2 * xs + 1], axis=1))
    assert centre == pytest.approx([1.0, 3.0])
    assert direction == pytest.approx(np.array([1.0, 2.0]) / math.sqrt(5.0))
    # A steep line: ordinary least squares in y(x) would fail; TLS gives the vertical direction.
    centre, direction = tls_line([[0.5, -1.0, 0.019], [0.5, 0.0, 0.019], [0.5, 2.0, 0.019]])
    assert centre == pytest.approx([0.5, 1 / 3])
    assert direction == pytest.approx([0.0, 1.0])
    # Symmetric offsets (x, y): (-1, 0), (0, 0.3), (1, 0): the line is y = 0.1 along x.
    centre, direction = tls_line([[-1.0, 0.0], [0.0, 0.3], [1.0, 0.0]])
    assert centre == pytest.approx([0.0, 0.1])
    assert direction == pytest.approx([1.0, 0.0])
    with pytest.raises(ValueError, match="tls_line"):
        tls_line(np.zeros((0, 2)))
    with pytest.raises(ValueError, match="tls_line"):
        tls_line([1.0, 2.0])


# ---------------------------------------------------------------------------------------------------
# pick_sort


def sorted_six():
    """pick_sort / sort_stack L2 blocks all on their sides: large at x > 0, small at x < 0, all y < 0."""
    return [block("L1", "red", "large", 0.10, -0.10), block("L2", "blue", "large", 0.20, -0.10),
            block("L3", "blue", "large", 0.15, -0.05), block("S1", "green", "small", -0.10, -0.10),
            block("S2", "violet", "small", -0.20, -0.10), block("S3", "red", "small", -0.15, -0.05)]


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
# pick_stack


def three_on_tag_2(dx=0.0, dy=0.0, tilts=None):
    return pile(0.25 + dx, -0.025 + dy, [("a", "red", "large"), ("b", "green", "large"), ("c", "blue", "large")],
                tilts)


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
# line_up


def rainbow_line(size, y, spacing, prefix, reverse=False, x0=-0.125):
    colors = list(reversed(RAINBOW)) if reverse else RAINBOW
    return [block(f"{prefix}{i}", color, size, x0 + spacing * i, y) for i, color in enumerate(colors)]


def test_line_up_order_read_in_the_better_direction_and_neatness():
    # Six in rainbow order 50 mm apart: 6 x 30 + 20 (length 250 mm).
    assert judge("line_up", 1, truth(rainbow_line("large", 0.2, 0.05, "b")), sim_time_s=300.0).points == 200
    # Laid right to left: read the other way, same points.
    assert judge("line_up", 1, truth(rainbow_line("large", 0.2, 0.05, "b", reverse=True)), sim_time_s=1.0).points == 200
    # 61 mm apart: length 305 mm, no neatness.
    assert judge("line_up", 1, truth(rainbow_line("large", 0.2, 0.061, "b")), sim_time_s=1.0).points == 180
    # Orange and red swapped: read left to right 10 + 10 + 4 x 30 = 140; right to left all six 10 = 60.
    swapped = rainbow_line("large", 0.2, 0.05, "b")
    swapped[0]["color"], swapped[1]["color"] = "orange", "red"
    assert judge("line_up", 1, truth(swapped), sim_time_s=1.0).points == 140


def test_line_up_straightness_30_10_0_by_distance_from_the_tls_line():
    # x = -125..125 mm; y offsets symmetric about x = 0, so the TLS line is y = mean = 0.2 + 25 mm:
    # offsets 0, 100, -25, -25, 100, 0 mm -> distances 25, 75, 50, 50, 75, 25 mm -> 30, 0, 10, 10, 0, 30.
    offsets_mm = [0, 100, -25, -25, 100, 0]
    line = [block(f"b{i}", color, "large", -0.125 + 0.05 * i, 0.2 + offsets_mm[i] / 1000.0)
            for i, color in enumerate(RAINBOW)]
    score = judge("line_up", 1, truth(line), sim_time_s=1.0)
    assert [r.points for r in rules_of(score, "line")] == [30, 0, 10, 10, 0, 30]
    assert score.points == 80


def test_line_up_level_2_excludes_stacked_and_tipped_blocks():
    large = rainbow_line("large", 0.2, 0.05, "L")
    small = rainbow_line("small", -0.1, 0.03, "S", x0=-0.075)
    assert judge("line_up", 2, truth(large, small), sim_time_s=1.0).points == 400
    # Small violet lifted onto the large violet: the small line has five blocks (5 x 30, no neatness).
    small[5]["position_m"] = [large[5]["position_m"][0], 0.2, 0.038 + 0.0125]
    assert judge("line_up", 2, truth(large, small), sim_time_s=1.0).points == 200 + 150
    # Large green tipped 20°: blue and violet move up one place (wrong rank, on the line: 10 each).
    large[3]["quat_wxyz"] = quat_tilt(20.0)
    assert judge("line_up", 2, truth(large, small), sim_time_s=1.0).points == 3 * 30 + 2 * 10 + 150


def test_line_up_level_3_distractors_50_mm_from_the_segments():
    large = rainbow_line("large", 0.2, 0.05, "L")  # segment x -125..125 mm at y = 200 mm
    small = rainbow_line("small", -0.1, 0.03, "S", x0=-0.075)
    score = judge("line_up", 3, truth(large, small, distractor("d1", 0.0, 0.251)), sim_time_s=1.0)
    assert (score.points, score.max_points, score.full) == (500, 500, True)
    close = judge("line_up", 3, truth(large, small, distractor("d1", 0.0, 0.249)), sim_time_s=1.0)
    assert close.points == 400
    assert rules_of(close, "distractors")[0].object_ids == ("d1",)
    # On the line's extension, 60 mm past the last block: far from the segment.
    beyond = judge("line_up", 3, truth(large, small, distractor("d1", 0.185, 0.2, "arch")), sim_time_s=1.0)
    assert beyond.points == 500


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


# ---------------------------------------------------------------------------------------------------
# Output and input


def test_score_is_frozen_and_serialises_to_json():
    score = judge("pick_sort", 1, truth(sorted_six()[:3]), sim_time_s=12.5)
    assert isinstance(score, Score)
    with pytest.raises(AttributeError):
        score.points = 5  # type: ignore[misc]
    data = json.loads(json.dumps(score.to_dict()))
    assert data["points"] == 3 * 30 + 10 and data["max_points"] == 100 and data["time_limit_s"] == 180.0
    assert data["full"] is True and data["within_limit"] is True
    assert data["breakdown"][0] == {"rule": "sorted", "points": 30, "detail": data["breakdown"][0]["detail"],
                                    "object_ids": ["L1"]}
    assert EVENT_LIMITS_S == {"pick_sort": 180, "pick_stack": 120, "line_up": 600, "stack_high": 600,
                              "to_the_sky": 600, "sort_stack": 180}


def test_judge_leaves_the_truth_unchanged():
    data = truth(three_on_tag_2())
    before = copy.deepcopy(data)
    judge("pick_stack", 1, data, sim_time_s=1.0, gripper_path_m=INSIDE_BOX_PATH_M)
    assert data == before


@pytest.mark.parametrize("call,match", [
    (lambda: judge("pick_and_place", 1, truth([]), sim_time_s=1.0), "unknown event"),
    (lambda: judge("pick_sort", 4, truth([]), sim_time_s=1.0), "levels"),
    (lambda: judge("stack_high", 3, truth([]), sim_time_s=1.0), "levels"),
    (lambda: judge("sort_stack", 0, truth([]), sim_time_s=1.0), "levels"),
    (lambda: judge("pick_sort", "1", truth([]), sim_time_s=1.0), "levels"),
    (lambda: judge("pick_sort", 1, [], sim_time_s=1.0), "'objects' list"),
    (lambda: judge("pick_sort", 1, {"objects": "none"}, sim_time_s=1.0), "'objects' list"),
    (lambda: judge("pick_sort", 1, {"objects": [{"id": "a", "type": "block"}]}, sim_time_s=1.0), "missing"),
    (lambda: judge("pick_sort", 1, truth([block("a", "pink", "large", 0, 0)]), sim_time_s=1.0), "color"),
    (lambda: judge("pick_sort", 1, truth([block("a", "red", "large", float("nan"), 0)]), sim_time_s=1.0), "finite"),
    (lambda: judge("pick_sort", 1, truth([block("a", "red", "large", 0, 0)] * 2), sim_time_s=1.0), "unique"),
    (lambda: judge("pick_sort", 1, truth([]), sim_time_s=-1.0), "sim_time_s"),
    (lambda: judge("pick_sort", 1, truth([]), sim_time_s=float("inf")), "sim_time_s"),
    (lambda: judge("pick_stack", 1, truth([]), sim_time_s=1.0, gripper_path_m=[[0.0, 0.1]]), "gripper_path_m"),
    (lambda: judge("pick_stack", 1, truth([]), sim_time_s=1.0, gripper_path_m=[[0.0, 0.1, float("nan")]]),
     "gripper_path_m"),
    (lambda: judge("pick_stack", 1, truth([]), sim_time_s=1.0, tag_centres_m=[]), "tag_centres_m"),
    (lambda: judge("pick_sort", 1, truth([]), sim_time_s=1.0, blocks_available=3), "to_the_sky only"),
])
def test_bad_input_is_refused_clearly(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_a_body_fallen_far_off_the_table_is_judged_not_refused():
    """The simulated table has no floor below it: a block pushed off it falls on without end. Its truth
    (tens of metres down) is judged where it is, off the board, instead of failing the run as malformed."""
    from armlab.tasks.scorers import score_job

    objects = sorted_six()
    objects[0]["position_m"] = [-0.45, 0.2, -42.0]  # fell off the table's edge on the wrong side
    score = judge("pick_sort", 2, truth(objects), sim_time_s=100.0)
    assert {r.object_ids[0]: r.points for r in rules_of(score, "sorted")}["L1"] == 0
    assert score.points == 5 * 30 and score.max_points == 200 and not score.full
    fallen = [distractor("c", 0.0, 0.0)]
    fallen[0]["position_m"] = [0.6, 0.1, -17.0]
    cleared = score_job("clear_table", truth(fallen), sim_time_s=30.0)
    assert cleared.points == 0
