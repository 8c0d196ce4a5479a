"""The station's state machine (DESIGN §6) as an explicit transition table.

`TRANSITIONS[state][command]` is the state the station enters when `command` is accepted in `state`;
a command missing from a state's row is refused with CommandRefused naming the row's commands.
Job-internal events (a job finishing, a device failing) have their own small table, `EVENTS`.
"""

from __future__ import annotations

from enum import Enum
from types import MappingProxyType

from armlab.errors import CommandRefused, InvalidInput


class State(str, Enum):
    IDLE = "idle"
    CALIBRATE = "calibrate"
    TEACH = "teach"
    REPEAT = "repeat"
    CLICK_GRAB = "click_grab"
    CLICK_DROP = "click_drop"
    AUTO_SORT = "auto_sort"
    ESTOP = "estop"
    FAULT = "fault"


# Operator commands (the names the REST API, the websocket and CommandRefused use).
COMMANDS = (
    "estop",
    "reset",
    "home",
    "sleep",
    "move_joints",
    "move_to",
    "jog",
    "torque",
    "gripper",
    "calibrate",
    "grab",
    "drop",
    "teach_start",
    "teach_record",
    "teach_stop",
    "teach_undo",
    "repeat",
    "auto",
    "cancel",
    "set_scene",
    "pause",
    "resume",
    "step",
    "set_speed",
)

_S = State
_MANUAL_MOVES = ("home", "sleep", "move_joints", "move_to", "jog", "torque", "gripper")

_TRANSITIONS: dict[State, dict[str, State]] = {
    _S.IDLE: {
        "estop": _S.ESTOP,
        **{name: _S.IDLE for name in _MANUAL_MOVES},
        "calibrate": _S.CALIBRATE,
        "grab": _S.CLICK_GRAB,
        "drop": _S.CLICK_DROP,
        "teach_start": _S.TEACH,
        "repeat": _S.REPEAT,
        "auto": _S.AUTO_SORT,
        "set_scene": _S.IDLE,
    },
    # Teaching: the operator positions the arm (jog, torque off on a real arm) and records waypoints.
    _S.TEACH: {
        "estop": _S.ESTOP,
        **{name: _S.TEACH for name in _MANUAL_MOVES},
        "teach_record": _S.TEACH,
        "teach_undo": _S.TEACH,
        "teach_stop": _S.IDLE,
    },
    # Job states: only e-stop and cancel; the job's end returns to idle (EVENTS below).
    _S.CALIBRATE: {"estop": _S.ESTOP, "cancel": _S.IDLE},
    # Repeat also takes the job controls: pause, resume, step (one waypoint while paused), speed override.
    _S.REPEAT: {"estop": _S.ESTOP, "cancel": _S.IDLE, "pause": _S.REPEAT, "resume": _S.REPEAT, "step": _S.REPEAT, "set_speed": _S.REPEAT},
    _S.CLICK_GRAB: {"estop": _S.ESTOP, "cancel": _S.IDLE},
    _S.CLICK_DROP: {"estop": _S.ESTOP, "cancel": _S.IDLE},
    _S.AUTO_SORT: {"estop": _S.ESTOP, "cancel": _S.IDLE},
    # Latched: only reset leaves; reset never moves the arm.
    _S.ESTOP: {"estop": _S.ESTOP, "reset": _S.IDLE},
    _S.FAULT: {"estop": _S.ESTOP, "reset": _S.IDLE},
}

# Read-only views: the table cannot be changed at run time.
TRANSITIONS = MappingProxyType({state: MappingProxyType(row) for state, row in _TRANSITIONS.items()})

JOB_STATES = (_S.CALIBRATE, _S.REPEAT, _S.CLICK_GRAB, _S.CLICK_DROP, _S.AUTO_SORT)

# Internal events: a job ended (any outcome other than a device failure) or a device failed.
EVENTS = MappingProxyType(
    {
        "job_ended": MappingProxyType({state: _S.IDLE for state in JOB_STATES}),
        "device_failed": MappingProxyType({state: _S.FAULT for state in State if state is not _S.ESTOP}),
    }
)


# The commands that need an arm: a station without one (perception only) refuses them whatever its state.
ARM_COMMANDS = frozenset(
    (*_MANUAL_MOVES, "grab", "drop", "teach_start", "teach_record", "teach_stop", "teach_undo", "repeat", "auto",
     "pause", "resume", "step", "set_speed")
)


def allowed_commands(state: State, has_arm: bool = True) -> list[str]:
    """The commands `state` accepts, in the canonical COMMANDS order (without ARM_COMMANDS when there is no arm)."""
    row = TRANSITIONS[State(state)]
    return [name for name in COMMANDS if name in row and (has_arm or name not in ARM_COMMANDS)]


def next_state(state: State, command: str) -> State:
    """The state after `command` in `state`; CommandRefused (naming the allowed commands) if not allowed."""
    if command not in COMMANDS:
        raise InvalidInput(f"unknown command '{command}'; known: {', '.join(COMMANDS)}")
    state = State(state)
    row = TRANSITIONS[state]
    if command not in row:
        raise CommandRefused(command, state.value, allowed_commands(state))
    return row[command]


def after_event(state: State, event: str) -> State:
    """The state after an internal event; unchanged when the event does not apply to `state`."""
    return EVENTS[event].get(State(state), State(state))
