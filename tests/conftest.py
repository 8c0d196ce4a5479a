"""Shared fixtures. MuJoCo renders offscreen on the CPU through EGL."""

import os

import pytest

from armlab.recording.lerobot.fair_threads import REALTIME_POLICIES

os.environ.setdefault("MUJOCO_GL", "egl")
# The simulation's default is config/sim.yaml's `realism` (camera: the camera shows a real L515's offset,
# noise, holes and drifting colour; real: the arm droops too). The suite's tests assert exact perception, so they run the ideal
# simulation whatever that default is, and so do the stations they start in subprocesses (the variable is inherited); a test of
# the realistic simulation asks for it explicitly (SimWorkcellConfig(realism="real"), `--realism real`).
os.environ["ARMLAB_REALISM"] = "ideal"


def pytest_collection_modifyitems(items):
    """Tests marked `long_first` go first (the suite runs on two workers, scripts/test: a test minutes long that
    started last would be the run's tail alone). And every test gets a node id of its own: schemathesis's
    per-operation tests (tests/server/schema_fuzz_cases.py) come out of pytest 9 all with the one id of their
    function, the operation only in their name; pytest-xdist hands out work by node id, so all but one of them would
    never run on a worker."""
    items.sort(key=lambda item: item.get_closest_marker("long_first") is None)  # stable: the rest keep their order
    for item in items:
        module_part, _, last = item.nodeid.rpartition("::")
        if item.name != last and item.name.startswith(last + "["):
            unique = f"{module_part}::{item.name}"
            try:  # pytest's private node id: structured (NodeId.parse) from 9.2, a string before
                if hasattr(item, "_id"):
                    item._id = type(item._id).parse(unique)
                else:
                    item._nodeid = unique
            except (AttributeError, TypeError, ValueError):
                return  # another pytest: ids stay as it makes them (only parallel runs need them unique)


STARTED_WITH_POLICY = os.sched_getscheduler(0) if hasattr(os, "sched_getscheduler") else None  # as the suite was started


@pytest.fixture(autouse=True)
def _the_test_process_stays_fairly_scheduled():
    """Fail the test after which the suite's own thread has become real-time (and put it back): SVT-AV1 run as root
    once left it SCHED_FIFO 99, and the Playwright driver and Chromium it started later inherited it and starved the
    machine for the rest of the run (armlab/recording/lerobot/fair_threads.py). Only a change from the policy the suite
    was started with counts (a suite started under batch, idle or real-time scheduling runs as it was started). One
    system call a test."""
    yield
    if STARTED_WITH_POLICY is None:
        return
    now = os.sched_getscheduler(0)
    if now != STARTED_WITH_POLICY and now in REALTIME_POLICIES:
        os.sched_setscheduler(0, STARTED_WITH_POLICY, os.sched_param(0))
        pytest.fail("the test process's thread is in real-time scheduling (SCHED_FIFO/RR) after this test or its fixtures")
