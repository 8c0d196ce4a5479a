"""The closed loop after a place (armlab.tasks.place_check, issue 19 item 4), on detections as a look gives them:
the residual of a placed block against its target is logged; later places on the same spot are shifted by what
remains, at most two corrections a spot, each limited to the clamp (said so); a residual far beyond the clamp is
not drift and is not chased; switched off, targets are unchanged and nothing is recorded."""

from __future__ import annotations

import numpy as np
import pytest
from seen_blocks import seen_block

from armlab.tasks.place_check import PlaceCheck

EDGE_M = 0.038


def detection(x_m: float, y_m: float, top_m: float = EDGE_M):
    return seen_block("red", "large", x_m, y_m, top_m)


@pytest.fixture
def log():
    return []


def checker(log, enabled=True, corrections=2, clamp_m=0.006) -> PlaceCheck:
    return PlaceCheck(enabled, corrections, clamp_m, lambda level, words: log.append((level, words)))


def place_and_look(check: PlaceCheck, to, seen_xy) -> dict:
    """Place at check.target_for(to), then a look sees the block at seen_xy; the new record."""
    at = check.target_for(to)
    check.placed(to, at, EDGE_M, "red large block")
    (record,) = check.check([detection(*seen_xy, top_m=to[2] + EDGE_M)])
    return record


def test_residual_logged_and_next_place_shifted_by_what_remains(log):
    check = checker(log)
    to = (0.10, 0.20, 0.0)
    first = place_and_look(check, to, (0.103, 0.196))  # the arm drifts +3, -4 mm here
    assert first["residual_mm"] == pytest.approx(5.0, abs=0.01) and first["correction"] == 1
    np.testing.assert_allclose(check.target_for(to)[:2], [0.097, 0.204], atol=1e-9)
    assert log[-1][0] == "info" and "sits 5.0 mm from its target" in log[-1][1] and "correction 1 of 2" in log[-1][1]
    # the arm drifts the same way: the shifted place lands 0.5 mm off; the second correction refines it
    second = place_and_look(check, to, (0.1005, 0.2))
    assert second["residual_mm"] == pytest.approx(0.5, abs=0.01) and second["shift_mm"] == [-3.0, 4.0]
    np.testing.assert_allclose(check.target_for(to)[:2], [0.0965, 0.204], atol=1e-9)
    # two corrections used: the third residual is logged, the shift kept
    third = place_and_look(check, (0.101, 0.201, 0.0), (0.102, 0.2))  # within the same spot
    assert third["note"] == "corrections used up" and "had its 2 corrections" in log[-1][1]
    np.testing.assert_allclose(check.target_for(to)[:2], [0.0965, 0.204], atol=1e-9)
    summary = check.summary()
    assert summary["checked"] == 3 and summary["max_mm"] == pytest.approx(5.0, abs=0.01)


def test_a_correction_beyond_the_clamp_is_limited_with_a_reason(log):
    check = checker(log, clamp_m=0.006)
    record = place_and_look(check, (0.0, 0.25, 0.0), (0.008, 0.25))  # 8 mm: over the 6 mm clamp, under 15 mm
    assert record["limited"] and record["correction_mm"] == [-6.0, 0.0]
    assert "limited to 6 mm" in log[-1][1]
    np.testing.assert_allclose(check.target_for((0.0, 0.25, 0.0)), [-0.006, 0.25, 0.0], atol=1e-9)


def test_far_off_is_not_drift_and_not_corrected(log):
    check = checker(log, clamp_m=0.006)
    record = place_and_look(check, (0.0, 0.25, 0.0), (0.02, 0.25))  # 20 mm: knocked, not the arm's drift
    assert record["note"] == "not drift: not corrected" and log[-1][0] == "warn"
    np.testing.assert_allclose(check.target_for((0.0, 0.25, 0.0)), [0.0, 0.25, 0.0])


def test_a_block_not_seen_at_its_target_is_said_and_not_corrected(log):
    check = checker(log)
    check.placed((0.0, 0.25, 0.0), (0.0, 0.25, 0.0), EDGE_M, "red large block")
    (record,) = check.check([detection(0.0, 0.25, top_m=2 * EDGE_M)])  # something there, but one block higher
    assert record["residual_mm"] is None and "not seen there" in log[-1][1]
    np.testing.assert_allclose(check.target_for((0.0, 0.25, 0.0)), [0.0, 0.25, 0.0])


def test_other_spots_are_not_shifted(log):
    check = checker(log)
    place_and_look(check, (0.10, 0.20, 0.0), (0.103, 0.196))
    np.testing.assert_allclose(check.target_for((0.15, 0.20, 0.0)), [0.15, 0.20, 0.0])


def test_switched_off_nothing_changes(log):
    check = checker(log, enabled=False)
    check.placed((0.10, 0.20, 0.0), (0.10, 0.20, 0.0), EDGE_M, "red large block")
    assert check.check([detection(0.103, 0.196)]) == [] and log == []
    np.testing.assert_allclose(check.target_for((0.10, 0.20, 0.0)), [0.10, 0.20, 0.0])


def test_a_refused_corrected_target_falls_back_to_the_intended_one_saying_why():
    from armlab.motion.safety import UnsafeTrajectory
    from armlab.tasks.place_check import first_passing_target

    planned, said = [], []

    def plan(target):  # the planner: refuses the corrected target (before anything moves)
        planned.append(np.round(np.asarray(target) * 1000, 1).tolist())
        if target[0] > 0.1:
            raise UnsafeTrajectory("the held block would meet the neighbour")
        return ["steps"]

    chosen = first_passing_target(plan, (0.105, 0.2, 0.0), (0.1, 0.2, 0.0), said.append)
    np.testing.assert_allclose(chosen, [0.1, 0.2, 0.0])
    assert planned == [[105.0, 200.0, 0.0], [100.0, 200.0, 0.0]]
    assert len(said) == 1 and "corrected place target (105.0, 200.0) mm is refused" in said[0] and "neighbour" in said[0]
    # a passing corrected target is used; a refused intended one is refused (nothing to fall back to)
    np.testing.assert_allclose(first_passing_target(plan, (0.095, 0.2, 0.0), (0.1, 0.2, 0.0), said.append), [0.095, 0.2, 0.0])
    with pytest.raises(UnsafeTrajectory):
        first_passing_target(plan, (0.11, 0.2, 0.0), (0.11, 0.2, 0.0), said.append)
