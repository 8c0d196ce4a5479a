"""A program's step tree (armlab.store.program_tree): expansion into the flat sequence repeat plans (loops,
nesting, waits as dwells, gripper steps), its limits, the store keeping a tree and an old flat program
unchanged, and the JSON file round trip (CSV flat)."""

from __future__ import annotations

import json
import sqlite3

import pytest

from armlab import program_io
from armlab.errors import InvalidInput
from armlab.store import Store, Waypoint
from armlab.store import program_tree as tree
from armlab.store.program_tree import Gripper, Group, Loop, Wait

A = Waypoint((0.1, 0.0, 0.0), "release")
B = Waypoint((0.2, 0.0, 0.0), "release")
C = Waypoint((0.3, 0.0, 0.0), "grasp")


def test_a_loop_repeats_its_body_and_a_group_runs_once():
    steps = (A, Loop(3, (B, C)), Group("place", (A,)))
    assert [w.joints_rad[0] for w in tree.expand(steps)] == [0.1, 0.2, 0.3, 0.2, 0.3, 0.2, 0.3, 0.1]


def test_nested_loops_multiply():
    steps = (A, Loop(2, (B, Loop(3, (C,)))))
    assert [w.joints_rad[0] for w in tree.expand(steps)] == [0.1] + [0.2, 0.3, 0.3, 0.3] * 2


def test_a_wait_is_a_dwell_on_the_waypoint_before_it_in_every_pass():
    flat = tree.expand((A, Loop(2, (B, Wait(0.5), Wait(0.25))), C))
    assert [w.dwell_s for w in flat] == [0.0, 0.75, 0.75, 0.0]
    assert B.dwell_s == 0.0  # the taught waypoint is not changed


def test_a_gripper_step_is_a_waypoint_at_the_previous_pose():
    flat = tree.expand((A, Gripper("close"), B, Gripper("open")))
    assert [(w.joints_rad[0], w.gripper) for w in flat] == [(0.1, "release"), (0.1, "grasp"), (0.2, "release"), (0.2, "release")]


@pytest.mark.parametrize(
    ("items", "where"),
    [
        ([{"kind": "loop", "count": 0, "body": [A.to_dict()]}], "steps[0].count"),
        ([{"kind": "loop", "count": 10**6, "body": [A.to_dict()]}], "steps[0].count"),
        ([A.to_dict(), {"kind": "wait", "seconds": float("nan")}], "steps[1].seconds"),
        ([A.to_dict(), {"kind": "wait", "seconds": "1"}], "steps[1].seconds"),
        ([A.to_dict(), {"kind": "group", "label": "", "body": [A.to_dict()]}], "steps[1].label"),
        ([A.to_dict(), {"kind": "jump"}], "steps[1].kind"),
        ([{"kind": "gripper", "action": "close"}, A.to_dict()], "steps[0]"),
    ],
)
def test_bad_steps_are_refused_naming_the_step(items, where):
    with pytest.raises(InvalidInput) as error:
        tree.expand(tree.steps_from_list(items))
    assert str(error.value).startswith(where), error.value


def test_nesting_deeper_than_the_limit_is_refused():
    item = A.to_dict()
    for _ in range(tree.MAX_DEPTH):
        item = {"kind": "group", "label": "g", "body": [item]}
    assert tree.depth(tree.steps_from_list([item])) == tree.MAX_DEPTH
    with pytest.raises(InvalidInput, match="nested more than 4 deep"):
        tree.steps_from_list([{"kind": "loop", "count": 2, "body": [item]}])


def test_loops_that_multiply_past_the_waypoint_limit_are_refused():
    steps = (A, Loop(1000, (Loop(1000, (B,)),)))
    with pytest.raises(InvalidInput, match="more than 1000 waypoints"):
        tree.expand(steps)


def test_the_store_keeps_a_tree_and_an_old_flat_row_reads_unchanged(tmp_path):
    store = Store(tmp_path / "s.sqlite3")
    steps = (A, Group("pick", (Loop(2, (B, Wait(1.0))), Gripper("close"))))
    saved = store.save_program("tree", steps)
    read = store.get_program(saved.id)
    assert read.steps == steps and read.waypoints == tree.expand(steps)
    flat = store.save_program("flat", [A, B])
    assert store.get_program(flat.id).steps is None
    row = sqlite3.connect(store.path).execute("SELECT waypoints_json FROM programs WHERE id = ?", (flat.id,)).fetchone()
    assert json.loads(row[0]) == [A.to_dict(), B.to_dict()]  # stored exactly as before trees existed
    old = sqlite3.connect(store.path)
    with old:  # a row written by a station from before step trees (no 'kind' anywhere)
        old.execute("INSERT INTO programs (name, created_s, waypoints_json) VALUES ('old', 1.0, ?)",
                    (json.dumps([{"joints_rad": [0.1, 0.0, 0.0], "gripper": "release", "dwell_s": 2.0}]),))
    legacy = [p for p in store.list_programs() if p.name == "old"][0]
    assert legacy.steps is None and legacy.waypoints == (Waypoint((0.1, 0.0, 0.0), "release", 2.0),)


def test_json_round_trips_the_tree_and_csv_is_the_expanded_sequence():
    steps = (A, Loop(2, (B, Wait(0.5), Gripper("close"))), Group("back", (A,)))
    flat = tree.expand(steps)
    text = program_io.to_json("t", flat, ["j1", "j2", "j3"], steps)
    document = json.loads(text)
    assert document["version"] == 2 and len(document["waypoints"]) == len(flat)
    name, parsed = program_io.parse_json(text, 3)
    assert name == "t" and tuple(parsed) == steps
    csv = program_io.to_csv(flat, [0.0] + [1.0] * (len(flat) - 1))
    def shape(waypoints):
        return [(w.joints_rad, w.gripper, w.dwell_s) for w in waypoints]

    assert shape(program_io.parse_csv(csv, 3)) == shape(flat)  # CSV is flat: loops unrolled, waits as dwells
    with pytest.raises(program_io.ProgramFileError, match=r"steps\[1\].count"):
        program_io.parse_json(json.dumps({"steps": [A.to_dict(), {"kind": "loop", "count": 0, "body": [B.to_dict()]}]}), 3)
