"""Random reachable layouts (not tied to a job): blocks and distractors of random size and colour, optionally
stacked and tagged."""

from __future__ import annotations

import numpy as np

from armlab.errors import InvalidInput
from armlab.scene.aruco_tops import with_aruco_tops
from armlab.scene.layout import block_items, board_regions, into_piles, place_piles
from armlab.scene.model import COLORS, DISTRACTOR_TYPES, SIZES, Scene, as_workcell
from armlab.workcell import Workcell


def random_scene(
    seed: int = 0,
    n_blocks: int | None = None,
    n_distractors: int | None = None,
    max_stack: int = 1,
    aruco: bool = False,
    workcell: Workcell | str | None = None,
) -> Scene:
    """A random reachable layout on `workcell` (None = the default): n_blocks (default 3..10) blocks of
    random size and colour, n_distractors (default 0..2) distractors, stacks up to max_stack high;
    aruco=True puts the workcell's block tags on blocks of their colours (aruco_ids_by_color)."""
    if max_stack < 1:
        raise InvalidInput("max_stack must be >= 1")
    rng = np.random.default_rng([int(seed), 99])
    n_blocks = int(rng.integers(3, 11)) if n_blocks is None else int(n_blocks)
    n_distractors = int(rng.integers(0, 3)) if n_distractors is None else int(n_distractors)
    if not (0 <= n_blocks <= 16 and 0 <= n_distractors <= 6):
        raise InvalidInput("random_scene: n_blocks must be 0..16 and n_distractors 0..6")
    sizes = [str(s) for s in rng.choice(SIZES, size=n_blocks)]
    colors = [str(c) for c in rng.choice(COLORS, size=n_blocks)]
    piles = into_piles(block_items(sizes, colors), max_stack, 0.35, rng)
    piles += [[(str(kind), None, str(rng.choice(COLORS)))] for kind in rng.choice(DISTRACTOR_TYPES, size=n_distractors)]
    workcell = as_workcell(workcell)
    scene = place_piles(piles, board_regions(workcell)["whole_board"], rng, workcell)
    return with_aruco_tops(scene) if aruco else scene
