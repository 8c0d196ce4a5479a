"""Program files (armlab.program_io): JSON and CSV round trips; malformed files refused naming the line."""

import pytest

from armlab.program_io import ProgramFileError, parse_csv, parse_json, to_csv, to_json
from armlab.store import Waypoint

NAMES = ("waist", "shoulder", "elbow", "wrist_angle", "wrist_rotate")
PROGRAM = [
    Waypoint((0.0, 0.1, 0.2, 0.3, 0.4), "release"),
    Waypoint((0.5, 0.1, 0.2, 0.3, 0.4), "release", 1.25, 2.0),
    Waypoint((0.5, 0.1, 0.2, 0.3, 0.4), "grasp"),  # a gripper step
    Waypoint((-0.5, 0.0, 0.1, 0.2, 0.0), "grasp"),
]


def test_json_round_trip_keeps_everything():
    name, waypoints = parse_json(to_json("demo", PROGRAM, NAMES), 5)
    assert name == "demo" and waypoints == PROGRAM


def test_csv_rows_are_timed_and_round_trip_dwells_and_gripper_steps():
    text = to_csv(PROGRAM, [0.0, 2.0, 0.0, 1.5])
    lines = text.splitlines()
    assert lines[0] == "t_s,q1,q2,q3,q4,q5,gripper"
    assert [float(line.split(",")[0]) for line in lines[1:]] == [0.0, 2.0, 3.25, 3.25, 4.75]  # the dwell is a repeated row
    back = parse_csv(text, 5)
    assert [w.gripper for w in back] == ["release", "release", "grasp", "grasp"]
    assert back[1].dwell_s == pytest.approx(1.25) and back[1].moving_time_s == pytest.approx(2.0)
    assert back[3].moving_time_s == pytest.approx(1.5) and back[2].moving_time_s is None
    for got, want in zip(back, PROGRAM):
        assert got.joints_rad == pytest.approx(want.joints_rad, abs=1e-9)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "line 1: the file is empty"),
        ("t,q1,q2,q3,q4,q5,gripper\n", "line 1: the header"),
        ("t_s,q1,q2,q3,q4,q5,gripper\n1,0,0,0,0,0,release\n", "line 2: the first t_s must be 0"),
        ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n1,0,0,nan,0,0,release\n", "line 3: q3 = 'nan' is not finite"),
        ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,release\n\n1,0,x,0,0,0,release\n", "line 4: q2 = 'x'"),
        ("t_s,q1,q2,q3,q4,q5,gripper\n0,0,0,0,0,0,open\n", "line 2: gripper = 'open'"),
    ],
)
def test_malformed_csv_names_the_line(text, message):
    with pytest.raises(ProgramFileError, match=message):
        parse_csv(text, 5)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{\n\"waypoints\": [1,\n}", "line 3"),
        ('{"format": "other"}', "format"),
        ('{"waypoints": [{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release", "speed": 3}]}', "waypoint 1: unknown field"),
        ('{"waypoints": [{"joints_rad": [0, 0, 0, 0, true], "gripper": "release"}]}', "waypoint 1: 'joints_rad' must be a list of numbers"),
        ('{"waypoints": [{"joints_rad": [0, 0, 0, 0, 0], "gripper": "release", "dwell_s": -1}]}', "waypoint 1: Waypoint.dwell_s"),
        ('[]', "no waypoints"),
    ],
)
def test_malformed_json_is_refused_with_the_reason(text, message):
    with pytest.raises(ProgramFileError, match=message):
        parse_json(text, 5)
