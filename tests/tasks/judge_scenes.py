"""Final states for the competition judge's tests (tests/tasks/test_judge*.py): blocks, distractors and piles
placed by hand, the truth dict the judge reads, and the sorted and stacked layouts more than one event's tests use."""

import math

import numpy as np

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


def sorted_six():
    """pick_sort / sort_stack L2 blocks all on their sides: large at x > 0, small at x < 0, all y < 0."""
    return [block("L1", "red", "large", 0.10, -0.10), block("L2", "blue", "large", 0.20, -0.10),
            block("L3", "blue", "large", 0.15, -0.05), block("S1", "green", "small", -0.10, -0.10),
            block("S2", "violet", "small", -0.20, -0.10), block("S3", "red", "small", -0.15, -0.05)]



def three_on_tag_2(dx=0.0, dy=0.0, tilts=None):
    return pile(0.25 + dx, -0.025 + dy, [("a", "red", "large"), ("b", "green", "large"), ("c", "blue", "large")],
                tilts)


