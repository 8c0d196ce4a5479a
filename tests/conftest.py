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


BROWSER_TESTS = "tests/web/"
# Files whose tests are each a work unit of their own (minutes each: the schema fuzz's shards).
ONE_UNIT_PER_TEST = ("tests/server/test_schema_fuzz.py",)


def _work_unit(nodeid: str) -> str:
    """What one pytest-xdist worker runs together (see pytest_xdist_make_scheduler): every browser test (one shared
    server and browser, in the order a single process runs them), each test of ONE_UNIT_PER_TEST alone, else a test
    file (its module-scoped fixtures set up once)."""
    path = nodeid.split("::", 1)[0]
    if path.startswith(BROWSER_TESTS):
        return BROWSER_TESTS
    return nodeid if path in ONE_UNIT_PER_TEST else path


def pytest_xdist_make_scheduler(config, log):
    """With `--dist loadfile` (scripts/test): loadfile's scheduling, in collection order, over _work_unit's units."""
    if config.getoption("dist", None) != "loadfile":
        return None
    from xdist.scheduler import LoadFileScheduling

    class WorkUnitScheduling(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return _work_unit(nodeid)

    return WorkUnitScheduling(config, log)


def pytest_collection_modifyitems(config, items):
    """Tests marked `long_first` go first, then (on pytest-xdist workers) the browser tests, one work unit minutes
    long: a long unit that started last would be the run's tail alone. And every test gets a node id of its own:
    schemathesis's per-operation tests (tests/server/schema_fuzz_cases.py) come out of pytest 9 all with the one id
    of their function, the operation only in their name; pytest-xdist hands out work by node id, so all but one of
    them would never run on a worker."""
    on_worker = os.environ.get("PYTEST_XDIST_WORKER") is not None

    def rank(item) -> int:
        if item.get_closest_marker("long_first") is not None:
            return 0
        return 1 if on_worker and item.nodeid.startswith(BROWSER_TESTS) else 2

    items.sort(key=rank)  # stable: the rest keep their order
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
