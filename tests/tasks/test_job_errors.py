"""A bug inside a job is an internal error, not a refusal (issue 20, item 3): the task runner catches the
planners' typed refusals (armlab.errors.PLAN_REFUSALS) only, so a bare ValueError (what numpy raises on
a shape mismatch) fails the job as "internal error" with its traceback logged, where it used to read as
"cannot pick the block" and the job went on."""

from __future__ import annotations

import logging

import pytest

from armlab.kinematics import Unreachable
from armlab.tasks import runner, start_auto

ONE_BLOCK = {"objects": [
    {"id": "red", "type": "block", "color": "red", "size": "large", "position_m": [0.10, 0.22, 0.019], "yaw_rad": 0.3},
]}
NUMPY_BUG = "operands could not be broadcast together with shapes (3,) (4,)"


@pytest.fixture()
def station(calibrated_station):
    """A synchronous station on a fast-mode simulation of ONE_BLOCK, calibrated."""
    return calibrated_station(ONE_BLOCK)


def test_a_bare_value_error_in_planning_fails_the_job_as_an_internal_error(station, monkeypatch, caplog):
    def buggy_plan_pick(*args, **kwargs):
        raise ValueError(NUMPY_BUG)

    monkeypatch.setattr(runner, "plan_pick", buggy_plan_pick)
    with caplog.at_level(logging.ERROR, logger="armlab.station.jobs"):
        job = start_auto(station, "pick_sort", 1)
        assert job.wait(300)
    assert job.state == "failed", job.message
    assert job.message.startswith("internal error: ValueError"), job.message
    failures = (job.to_dict()["extra"].get("task") or {}).get("failures", [])
    assert not any("cannot pick" in failure for failure in failures), failures
    logged = [r for r in caplog.records if r.levelno >= logging.ERROR and r.exc_info and NUMPY_BUG in str(r.exc_info[1])]
    assert logged, "the traceback of the bug was not logged at ERROR"


def test_an_unreachable_block_is_still_a_refusal_the_job_goes_on_from(station, monkeypatch):
    def unreachable_pick(*args, **kwargs):
        raise Unreachable("target (0.1, 0.22, 0.02) m: out of reach", "out of reach")

    monkeypatch.setattr(runner, "plan_pick", unreachable_pick)
    job = start_auto(station, "pick_sort", 1)
    assert job.wait(300)
    assert not job.message.startswith("internal error"), job.message
    failures = job.to_dict()["extra"]["task"]["failures"]
    assert any("cannot pick the red large block" in failure and "out of reach" in failure for failure in failures), failures


@pytest.mark.parametrize("step", ["plan_place", "run_steps"])
def test_a_bare_value_error_in_a_later_step_is_no_refusal_either(station, monkeypatch, step):
    """The place's planning (tried at the corrected target, then the intended one: first_passing_target) and the
    running of planned steps: a bug there fails the job as an internal error too, never "cannot place" or the
    like, and the job does not go on to another move."""
    calls = []

    def buggy(*args, **kwargs):
        calls.append(step)
        raise ValueError(NUMPY_BUG)

    monkeypatch.setattr(runner, step, buggy)
    job = start_auto(station, "pick_sort", 1)
    assert job.wait(300)
    assert job.state == "failed" and job.message.startswith("internal error: ValueError"), (job.state, job.message)
    assert calls == [step], calls  # raised once: nothing caught it and tried again
    failures = (job.to_dict()["extra"].get("task") or {}).get("failures", [])
    assert not any("cannot" in failure or "unreachable" in failure for failure in failures), failures
