"""armlab eval on the real arm (realism real): the arm is calibrated from the camera before the job's clock starts
(the job then parks from the sleep pose by a way the calibrated, drooping arm clears its base by: before the
front via in runner.park it failed at t = 0 with 'the gripper point would reach the arm's own base'), and pick_sort
L1 seed 0 scores full points; --no-arm-calibration runs it uncalibrated (the job clock excludes neither)."""

from __future__ import annotations

import pytest

from armlab.tasks.episode import run_episode

pytestmark = pytest.mark.slow


def test_pick_sort_on_the_calibrated_real_arm_scores_full_points():
    run = run_episode("pick_sort", 1, 0, realism="real")
    assert run["full"] and not run["failures"], run["failures"]
