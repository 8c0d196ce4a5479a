"""The competition judge's line_up event (DESIGN §7, armlab/tasks/judge/lines.py), on hand-made final states
whose scores are worked out by hand here."""

from judge_scenes import (
    RAINBOW,
    block,
    distractor,
    quat_tilt,
    rules_of,
    truth,
)

from armlab.tasks.judge import judge

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
