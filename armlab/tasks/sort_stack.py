"""sort_stack (DESIGN §7, the 2024-26 "Sort 'n stack"): every block to its side (y < 0; small x < 0,
large x > 0) and, at L2/L3, in its side's single column in rainbow order; distractors stay at y > 0.
L1 only sorts (pick_sort's slots); L2/L3 build one ordered column per side, piles uncovered at y > 0."""

from __future__ import annotations

from armlab.tasks import pick_sort
from armlab.tasks.ordered_columns import make_ordered_policy
from armlab.tasks.runner import TaskRunner

COLUMN_BASES_M = {"large": (0.20, -0.10), "small": (-0.20, -0.10)}
ASIDE_REGION_M = ((-0.30, 0.30), (0.10, 0.32))


def make_policy(level: int | None, params: dict, runner: TaskRunner):
    if level == 1:
        return pick_sort.policy
    return make_ordered_policy(runner, COLUMN_BASES_M, aside_region=ASIDE_REGION_M)
