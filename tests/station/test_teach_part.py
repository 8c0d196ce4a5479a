"""Teach on its own (armlab.station.teach: Teach and its ContinuousRecorder), without a station or a simulation: a
real SQLite store, the gate's checks and state changes as fakes. A recorded waypoint is in the draft when record
returns; a refused command writes nothing; two writes never interleave (the second is refused, as is leaving teach
during one); save empties the draft and leaves teach only while still in it; the recorder's last pose, its refusals
and its death as a fault."""

from __future__ import annotations

import sqlite3
import threading

import numpy as np
import pytest

from armlab.errors import CommandRefused, InvalidInput, NotController
from armlab.station.teach import ContinuousRecorder, Teach, TeachLinks
from armlab.store import Owner, Store

OWNER = Owner("rx200", "test", 5)
JOIN_S = 10.0  # bound on a thread's end; the tests wait on events, never on time


class Gate:
    """The gate as teach sees it: a state, refusals on demand, the arm's readings; records every call."""

    def __init__(self) -> None:
        self.state, self.refuse, self.latched, self.closing = "teach", None, False, False
        self.q = np.zeros(5)
        self.gripper = "release"
        self.transitions: list[tuple] = []
        self.failures: list[tuple[str, str]] = []
        self.bad_pose = False
        self.moving, self.reads = False, 0  # moving: each reading of the joints is a new pose

    def read_joints(self) -> np.ndarray:
        self.reads += 1
        return self.q + 0.1 * self.reads if self.moving else self.q.copy()

    def allowed_or_raise(self, command, source):
        if self.refuse is not None:
            raise self.refuse

    def transition(self, command, source, detail, only_in_teach):
        self.transitions.append((command, detail, only_in_teach))
        if not only_in_teach or self.state == "teach":
            self.state = "idle" if command == "teach_stop" else "teach"

    def check_pose(self, q):
        if self.bad_pose:
            raise ValueError("the fingers would be in the board")

    def links(self, threads: bool = True) -> TeachLinks:
        return TeachLinks(self.allowed_or_raise, self.transition, lambda: self.state == "teach" and not self.latched,
                          lambda: self.closing, self.read_joints, lambda: self.gripper, self.check_pose,
                          lambda poses: [self.check_pose(q) for q in poses], lambda what, why: self.failures.append((what, why)),
                          threads)


class Events:
    def __init__(self) -> None:
        self.messages: list[str] = []

    def add(self, level, message) -> None:
        self.messages.append(message)


@pytest.fixture()
def setup(tmp_path):
    gate, store = Gate(), Store(tmp_path / "teach.sqlite3")
    return gate, store, Teach(store, Events(), lambda: OWNER, gate.links())


def test_a_recorded_waypoint_is_in_the_draft_when_record_returns(setup):
    gate, store, teach = setup
    gate.q, gate.gripper = np.array([0.1, 0.2, 0.3, 0.4, 0.5]), "grasp"
    waypoint, count = teach.record(dwell_s=0.5)
    assert count == 1 and waypoint.gripper == "grasp" and waypoint.dwell_s == 0.5
    assert Store(store.path).read_draft(OWNER)[0] == [waypoint]  # committed: another connection reads it
    assert gate.transitions == [("teach_record", "teaching: 1 waypoints", False)]


def test_a_gripper_neither_grasping_nor_releasing_records_release(setup):
    gate, _, teach = setup
    gate.gripper = "moving"
    assert teach.record()[0].gripper == "release"


def test_a_refused_record_writes_nothing(setup):
    gate, store, teach = setup
    gate.refuse = NotController("teach_record", "someone else")
    with pytest.raises(NotController):
        teach.record(source="me")
    assert store.read_draft(OWNER)[0] == [] and gate.transitions == []


def test_a_pose_no_move_may_reach_is_not_recorded(setup):
    gate, store, teach = setup
    gate.bad_pose = True
    with pytest.raises(ValueError, match="this pose is not recorded: the fingers"):
        teach.record()
    assert store.read_draft(OWNER)[0] == []


class BlockingStore(Store):
    """A store whose append_draft waits for `release` once `entered` is set: a write in progress."""

    def __init__(self, path) -> None:
        super().__init__(path)
        self.entered, self.release = threading.Event(), threading.Event()

    def append_draft(self, waypoint, owner=None):
        self.entered.set()
        assert self.release.wait(JOIN_S)
        return super().append_draft(waypoint, owner)


def test_a_second_write_and_leaving_teach_are_refused_while_a_write_is_under_way(tmp_path):
    gate, store = Gate(), BlockingStore(tmp_path / "teach.sqlite3")
    teach = Teach(store, Events(), lambda: OWNER, gate.links())
    first = threading.Thread(target=teach.record)
    first.start()
    assert store.entered.wait(JOIN_S)
    with pytest.raises(CommandRefused, match="busy saving"):
        teach.undo()
    with pytest.raises(CommandRefused, match="busy saving"):
        teach.exit()
    with pytest.raises(CommandRefused, match="busy saving"):
        teach.stop("during a write")
    store.release.set()
    first.join(JOIN_S)
    assert len(store.read_draft(OWNER)[0]) == 1 and gate.state == "teach"
    teach.undo()  # free again
    assert store.read_draft(OWNER)[0] == []


def test_stop_saves_the_draft_empties_it_and_leaves_teach(setup):
    gate, store, teach = setup
    teach.record()
    gate.q = np.full(5, 0.2)
    teach.record()
    program = teach.stop("two points")
    assert len(program.waypoints) == 2 and store.read_draft(OWNER)[0] == []
    assert gate.transitions[-1] == ("teach_stop", "", True) and gate.state == "idle"


def test_an_e_stop_during_the_save_keeps_the_program_and_the_state(setup):
    gate, store, teach = setup
    teach.record()
    gate.state = "estop"  # latched while the program was being written: the transition is only made in teach
    program = teach.stop("saved under e-stop")
    assert store.get_program(program.id, OWNER).name == "saved under e-stop" and gate.state == "estop"


def test_start_resumes_a_draft_unless_it_is_discarded(setup):
    gate, _, teach = setup
    teach.record()
    assert len(teach.start()) == 1 and gate.transitions[-1][1] == "teaching: 1 waypoints (draft resumed)"
    assert teach.start(discard_draft=True) == [] and teach.draft() == []


def test_continuous_recording_is_refused_without_threads_or_at_a_bad_rate(tmp_path):
    gate = Gate()
    teach = Teach(Store(tmp_path / "t.sqlite3"), Events(), lambda: OWNER, gate.links(threads=False))
    with pytest.raises(InvalidInput, match="real-time station"):
        teach.continuous(5.0)
    teach = Teach(Store(tmp_path / "t.sqlite3"), Events(), lambda: OWNER, gate.links())
    for rate_hz in (0.1, 50.0):
        with pytest.raises(InvalidInput, match="rate_hz"):
            teach.continuous(rate_hz)
    assert not teach.has_recorder


def test_the_recorder_records_the_last_pose_when_stopped(setup):
    """A stop before the first tick still records where the arm went (a late tick must not cut the motion's end off)."""
    gate, store, teach = setup
    recorder = teach.continuous(0.5)  # one tick every 2 s: the stop comes first
    gate.q = np.full(5, 0.3)
    assert teach.continuous_stop() == 1 and not recorder.is_alive() and not teach.has_recorder
    waypoints = store.read_draft(OWNER)[0]
    assert len(waypoints) == 1 and waypoints[0].joints_rad == (0.3,) * 5 and waypoints[0].moving_time_s >= 2.0


def test_the_recorder_skips_a_pose_that_did_not_change(setup):
    gate, store, teach = setup
    teach.continuous(0.5)
    assert teach.continuous_stop() == 0 and store.read_draft(OWNER)[0] == []


def record_raising(error: Exception):
    def record(moving_time_s: float):
        raise error
    return record


def test_a_recorder_dying_on_the_database_is_a_fault(setup):
    gate = Gate()
    recorder = ContinuousRecorder(gate.links(), record_raising(sqlite3.DatabaseError("database disk image is malformed")), 0.5, 0.01)
    gate.moving = True
    recorder.start()
    recorder.stop(JOIN_S)
    assert not recorder.is_alive()
    assert len(gate.failures) == 1 and gate.failures[0][0] == "teach recorder"
    assert "DatabaseError" in gate.failures[0][1] and "after 0 waypoints" in gate.failures[0][1]
    assert "DatabaseError" in recorder.error


def test_a_recorder_refused_once_teach_ended_stops_without_a_fault():
    gate = Gate()
    recorder = ContinuousRecorder(gate.links(), record_raising(CommandRefused("teach_record", "idle", [])), 0.5, 0.01)
    gate.moving, gate.state = True, "idle"
    recorder.start()
    recorder.stop(JOIN_S)
    assert not recorder.is_alive() and gate.failures == [] and "teach_record" in recorder.error


def test_a_recorder_losing_the_lease_stops_without_a_fault():
    gate = Gate()
    recorder = ContinuousRecorder(gate.links(), record_raising(NotController("teach_record", "other")), 0.5, 0.01)
    gate.moving = True
    recorder.start()
    recorder.stop(JOIN_S)
    assert gate.failures == [] and "other" in recorder.error


def test_a_recorder_refused_while_still_teaching_goes_on():
    """The operator's own record or undo was being written: the recorder tries again at its next tick."""
    gate = Gate()
    recorder = ContinuousRecorder(gate.links(), record_raising(CommandRefused("teach_record", "teach (busy saving)", [])), 0.5, 0.01)
    gate.moving = True
    recorder.start()
    recorder.stop(JOIN_S)
    assert not recorder.is_alive() and recorder.error is None and gate.failures == []
