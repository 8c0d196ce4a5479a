"""pick_sort's slots (hand-made inputs): a slot where the depth image measures something standing is not
free even when no detection is there (the arm partly hid a block placed there: pick_sort L3 seed 9 put
a second block on it)."""

from __future__ import annotations

import math

from seen_blocks import seen_block

from armlab.tasks import pick_sort


def block(color, size, x, y, z_top):
    return seen_block(color, size, x, y, z_top)


def test_a_slot_with_something_measured_standing_on_it_is_skipped():
    objects = [block("red", "large", -0.157, 0.138, 0.038)]
    first = pick_sort.policy(objects, set(), lambda xy: 0.0).moves[0].to_m[:2]  # where it goes on an empty side
    assert first[0] > 0 and first[1] < 0

    def standing_at(xy):  # a large block stands on that slot, undetected
        return 0.038 if math.dist(xy, first) < 0.01 else 0.0

    target = pick_sort.policy(objects, set(), standing_at).moves[0].to_m
    assert math.dist(target[:2], first) > 0.05
    assert target[0] > 0 and target[1] < 0  # still the large side
