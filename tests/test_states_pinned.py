"""The state machine pinned to DESIGN §6, cell by cell, written out by hand (never read back from
armlab.station.states): a change to the table (teach accepting `grab`, a job state accepting a move,
reset leaving fault without a device check...) must change this file too.

§6: states idle, calibrate, teach, repeat, click_grab, click_drop, auto_sort, estop, fault. E-stop is
reachable from every state and latches; reset returns to idle from estop and fault only. Idle accepts
the manual commands, the jobs, teach and scene changes; teach accepts the manual commands (jog, torque
off to move the arm by hand) and its own record/undo/stop; a job state accepts only e-stop and cancel (repeat
also its pause, resume, step and speed override, issue 9); the
job's end returns to idle, a device failure to fault (from any state but estop, which stays latched).
"""

from __future__ import annotations

import pytest

from armlab.errors import CommandRefused
from armlab.station.states import COMMANDS, EVENTS, State, after_event, allowed_commands, next_state

I, CAL, T, R, CG, CD, A, E, F = (  # noqa: E741 (one letter a state: the table below reads as a grid)
    State.IDLE, State.CALIBRATE, State.TEACH, State.REPEAT, State.CLICK_GRAB, State.CLICK_DROP, State.AUTO_SORT, State.ESTOP, State.FAULT,
)

ALL_COMMANDS = [
    "estop", "reset", "home", "sleep", "move_joints", "move_to", "jog", "torque", "gripper", "calibrate", "grab", "drop",
    "teach_start", "teach_record", "teach_stop", "teach_undo", "repeat", "auto", "cancel", "set_scene",
    "pause", "resume", "step", "set_speed",
]

# EXPECTED[state][command] = the next state; a command absent from a row is refused in that state.
EXPECTED = {
    I: {
        "estop": E, "home": I, "sleep": I, "move_joints": I, "move_to": I, "jog": I, "torque": I, "gripper": I,
        "calibrate": CAL, "grab": CG, "drop": CD, "teach_start": T, "repeat": R, "auto": A, "set_scene": I,
    },
    T: {
        "estop": E, "home": T, "sleep": T, "move_joints": T, "move_to": T, "jog": T, "torque": T, "gripper": T,
        "teach_record": T, "teach_undo": T, "teach_stop": I,
    },
    CAL: {"estop": E, "cancel": I},
    R: {"estop": E, "cancel": I, "pause": R, "resume": R, "step": R, "set_speed": R},
    CG: {"estop": E, "cancel": I},
    CD: {"estop": E, "cancel": I},
    A: {"estop": E, "cancel": I},
    E: {"estop": E, "reset": I},
    F: {"estop": E, "reset": I},
}

JOB_ENDED = {CAL: I, R: I, CG: I, CD: I, A: I}  # other states: unchanged
DEVICE_FAILED = {I: F, CAL: F, T: F, R: F, CG: F, CD: F, A: F, F: F}  # estop: unchanged (latched)


def test_the_commands_are_the_pinned_ones():
    assert list(COMMANDS) == ALL_COMMANDS
    assert set(EXPECTED) == set(State)


@pytest.mark.parametrize("state", list(State), ids=lambda s: s.value)
@pytest.mark.parametrize("command", ALL_COMMANDS)
def test_every_cell(state, command):
    if command in EXPECTED[state]:
        assert next_state(state, command) is EXPECTED[state][command]
    else:
        with pytest.raises(CommandRefused) as refused:
            next_state(state, command)
        assert refused.value.allowed == [name for name in ALL_COMMANDS if name in EXPECTED[state]]


@pytest.mark.parametrize("state", list(State), ids=lambda s: s.value)
def test_allowed_commands_in_canonical_order(state):
    assert allowed_commands(state) == [name for name in ALL_COMMANDS if name in EXPECTED[state]]


@pytest.mark.parametrize("state", list(State), ids=lambda s: s.value)
def test_internal_events(state):
    assert after_event(state, "job_ended") is JOB_ENDED.get(state, state)
    assert after_event(state, "device_failed") is DEVICE_FAILED.get(state, state)
    assert set(EVENTS) == {"job_ended", "device_failed"}
