"""Detection labels on the streamed camera views are readable and never overlap (issue 9 item 6)."""

from __future__ import annotations

import itertools

import cv2

from armlab.vision.overlay import LABEL_SCALE, place_label


def overlap(a, b) -> bool:
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def test_labels_of_blocks_side_by_side_and_stacked_do_not_overlap():
    (w, h), baseline = cv2.getTextSize("violet large L2", cv2.FONT_HERSHEY_SIMPLEX, LABEL_SCALE, 1)
    size = (w + 6, h + baseline + 6)
    # A stack (same pixel), two touching blocks, and a row along the image's top edge.
    anchors = [(640, 360)] * 3 + [(700, 360), (725, 365)] + [(40 + 30 * i, 12) for i in range(5)]
    placed = []
    for anchor in anchors:
        placed.append(place_label(anchor, size, placed, (1280, 720)))
    for a, b in itertools.combinations(placed, 2):
        assert not overlap(a, b), (a, b)
    assert all(0 <= x and 0 <= y and x + bw <= 1280 and y + bh <= 720 for x, y, bw, bh in placed)


def test_label_text_is_readable_at_the_streamed_size():
    (_, cap_h), _ = cv2.getTextSize("H", cv2.FONT_HERSHEY_SIMPLEX, LABEL_SCALE, 1)
    assert cap_h >= 12  # px in the 1280 x 720 image (the old 0.4 scale gave 9 px capitals)
