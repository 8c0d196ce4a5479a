"""The competition judge (DESIGN §7): the definitions (upright, on the board, columns, TLS line), the score's
output and bad input. Each event's rules, on hand-made final states scored by hand: test_judge_sorting.py,
test_judge_stacking.py, test_judge_line_up.py; the shared final states: judge_scenes.py."""

import copy
import json
import math

import numpy as np
import pytest
from judge_scenes import (
    INSIDE_BOX_PATH_M,
    block,
    distractor,
    pile,
    rules_of,
    sorted_six,
    three_on_tag_2,
    truth,
)

from armlab.tasks.judge import EVENT_LIMITS_S, Score, columns, judge, on_board, tls_line, upright

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
