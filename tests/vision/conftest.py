"""Fixtures for perception tests: the config, synthetic board frames with exact ground truth."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from armlab.vision import load_perception_config  # noqa: E402
from synth import L515, look_at_pose, render_board, render_sim  # noqa: E402


@pytest.fixture(scope="session")
def cfg():
    return load_perception_config()


@pytest.fixture(scope="session")
def board_pose():
    """A camera 1 m above the board near (-40, 400) mm, tilted ~12 degrees, like the sim mount."""
    return look_at_pose((-0.04, 0.40, 1.0), (0.0, 0.19, 0.0))


@pytest.fixture(scope="session")
def board_frame(board_pose):
    color, depth = render_board(board_pose)
    return color, depth


@pytest.fixture(scope="session")
def intrinsics():
    return L515


@pytest.fixture(scope="session")
def event_frame():
    """line_up level 3: stacks up to 4 of mixed sizes and distractors; the rig is bumped (seed 1)."""
    from armlab.scene import generate_scene

    return render_sim(generate_scene("line_up", level=3, seed=1), seed=1)
