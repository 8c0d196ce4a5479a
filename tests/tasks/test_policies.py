"""The pure parts of the jobs: clearance between the arm and boxes, finger directions, columns read
from measurements, line layouts clear of distractors, pick_sort's targets (hand-made inputs)."""

from __future__ import annotations

import math

import pytest
from seen_blocks import seen_block

from armlab.kinematics import load_arm
from armlab.motion import plan_joint_move
from armlab.motion.clearance import box_around, first_collision
from armlab.tasks import pick_sort
from armlab.tasks.columns import Column
from armlab.tasks.line_up import segment_distance
from armlab.tasks.policy import finger_axis_away

ARM = load_arm("rx200")


block = seen_block


def test_a_move_through_a_tall_box_collides_and_a_move_above_it_does_not():
    q_a = ARM.ik([0.20, 0.10, 0.05], pitch=math.pi / 2)
    q_b = ARM.ik([-0.20, 0.10, 0.05], pitch=math.pi / 2)
    low = plan_joint_move(q_a, q_b, ARM)
    tower = box_around("tower", (0.0, 0.22), 0.03, 0.30)  # stands in the way of the sweep
    pebble = box_around("pebble", (0.0, 0.40), 0.02, 0.01)  # far outside it
    assert first_collision(ARM, low, [tower]) is not None
    assert first_collision(ARM, low, [pebble]) is None
    q_c = ARM.ik([0.20, 0.10, 0.40], pitch=0.0)
    q_d = ARM.ik([-0.20, 0.10, 0.40], pitch=0.0)
    assert first_collision(ARM, plan_joint_move(q_c, q_d, ARM), [box_around("short", (0.0, 0.25), 0.03, 0.05)]) is None


def test_fingers_open_across_the_direction_of_a_close_neighbour():
    here = [0.10, 0.20, 0.038]
    east = block("red", "large", 0.16, 0.20, 0.038)  # 60 mm along +x
    axis = finger_axis_away(here, 0.0, [east])
    assert abs(math.cos(axis)) < 1e-9  # fingers along y, never toward the neighbour along x
    far = block("red", "large", 0.30, 0.20, 0.038)
    assert finger_axis_away(here, 0.0, [far]) is None


def test_a_column_trusts_the_measured_height_over_its_memory():
    column = Column("c", (0.1, 0.2))
    for color in ("red", "orange", "yellow"):
        column.add(block(color, "large", 0.1, 0.2, 0.0), 0.038)
    top = block("yellow", "large", 0.101, 0.2, 0.114, level=3)
    column.observe([top], lambda xy: 0.114)
    assert column.height == 3 and column.top is top
    assert column.surface_m() == pytest.approx((0.101, 0.2, 0.114))
    column.observe([], lambda xy: 0.076)  # the top block fell off: two remain
    assert [b.color for b in column.placed] == ["red", "orange"]
    assert column.surface_m() == pytest.approx((0.1, 0.2, 0.076))  # no detection: over the base
    column.observe([], lambda xy: 0.0)
    assert column.height == 0 and column.surface_m() == (0.1, 0.2, 0.0)


def test_pick_sort_sends_each_size_to_its_side_and_finishes_when_sorted():
    objects = [block("red", "large", 0.1, 0.25, 0.076, level=2), block("blue", "small", -0.1, 0.2, 0.025)]
    plan = pick_sort.policy(objects, set())
    assert not plan.finished and plan.left == 3 and plan.done == 0  # one hidden under the pile
    first = plan.moves[0]
    assert first.block is objects[0]  # the pile top first: it uncovers a block
    assert first.to_m[0] > 0 and first.to_m[1] < 0
    small = next(m for m in plan.moves if m.block.size == "small")
    assert small.to_m[0] < 0 and small.to_m[1] < 0
    done = [block("red", "large", 0.15, -0.1, 0.038), block("blue", "small", -0.15, -0.1, 0.025)]
    assert pick_sort.policy(done, set()).finished


def test_segment_distance():
    assert segment_distance((0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)) == pytest.approx(1.0)
    assert segment_distance((3.0, 0.0), (-1.0, 0.0), (1.0, 0.0)) == pytest.approx(2.0)  # beyond the end
