"""The library's error hierarchy; the server maps it to HTTP in one place (server/errors.py).

ArmlabError
├── InvalidInput (ValueError)      a value the caller gave is wrong; nothing moved (ConfigError, ...)
├── Unreachable (ValueError)       no joint vector reaches the target within the limits
├── RefusedByCheck                 a check refused the command: state, lease, calibration (CommandRefused, ...)
│   ├── WrongArm                   a program taught on another arm or workcell
│   └── PlanRefused (ValueError)   no motion passes the planner's checks (UnsafeTrajectory, DiscontinuousPath)
└── DeviceFault (ConnectionError)  a device is not connected, stopped answering or timed out

Anything else (a bare ValueError from numpy, a KeyError, ...) is a bug: HTTP 500 and a failed job that
says "internal error", with the traceback logged.
"""

from __future__ import annotations


class ArmlabError(Exception):
    """The base of every error the library raises on purpose (its callers catch these, never bare ValueError)."""


class InvalidInput(ArmlabError, ValueError):
    """A value the caller supplied is invalid (a field, a parameter, a file); the message names it. Nothing moved."""


class Unreachable(ArmlabError, ValueError):
    """No joint vector reaches the target within the limits.

    The message says why: "out of reach", "joint limit (<joint name>)" or "below the table", with the
    numbers. `reason` holds that short phrase alone, for callers that branch on it.
    """

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason


class RefusedByCheck(ArmlabError):
    """A check refused the command: the station's state, the control lease, the calibration, a motion or
    collision check. Subclasses say which (HTTP 409 for state-like refusals, 422 for unsafe motion)."""


class PlanRefused(RefusedByCheck, ValueError):
    """A planner found no motion that passes its checks: unsafe (UnsafeTrajectory), discontinuous, too fast
    near a singularity, outside the gripper box, no jerk-limited trajectory. Nothing moved."""


class SpotHidden(RefusedByCheck):
    """A clicked spot is hidden (under the arm) and may have changed since it was last seen: its height is not
    guessed (HTTP 409); the message says how to see it."""


class WrongArm(RefusedByCheck):
    """A stored item (a taught program) belongs to another arm or workcell than this station's (HTTP 409): its
    joints mean nothing here. The message names both."""


class DeviceFault(ArmlabError, ConnectionError):
    """A device is not connected, stopped answering, or cannot be used (HTTP 503)."""



class DeviceNotConnectedError(DeviceFault):
    """A device method was called before connect() (or after close())."""

    def __init__(self, message: str = "device is not connected: call connect() first") -> None:
        super().__init__(message)


class DeviceAlreadyConnectedError(DeviceFault):
    """connect() was called on a device that is already connected."""

    def __init__(self, message: str = "device is already connected: call close() before connecting again") -> None:
        super().__init__(message)


class ConfigError(InvalidInput):
    """A configuration file or field is invalid; the message names the file and the field."""


class CommandRefused(RefusedByCheck, RuntimeError):
    """A station command is not allowed in the current state.

    Attributes:
        state: the state the station is in.
        allowed: the commands that state accepts.
    """

    def __init__(self, command: str, state: str, allowed: list[str] | tuple[str, ...]) -> None:
        self.command = command
        self.state = state
        self.allowed = list(allowed)
        super().__init__(
            f"command '{command}' is not allowed in state '{state}'; allowed: {', '.join(self.allowed) or 'none'}"
        )


class NotController(RefusedByCheck, RuntimeError):
    """A control command from a client that does not hold the control lease (HTTP 409).

    Attributes:
        controller: who holds the lease.
    """

    def __init__(self, command: str, controller: str) -> None:
        self.command = command
        self.controller = controller
        super().__init__(
            f"command '{command}' refused: the station is controlled by '{controller}'; "
            "take control first (POST /api/control/take; the current controller is told)"
        )


class CalibrationUntrusted(RefusedByCheck, RuntimeError):
    """A grab, drop or autonomous job refused because the camera-moved check no longer confirms the
    calibration in use (HTTP 409 'not_calibrated'); the message gives the reason. Recalibrate, or let
    the board tags confirm the camera again."""


class NeedsConfirmation(RefusedByCheck, RuntimeError):
    """A command that is dangerous in the current state and was sent without confirm: true (HTTP 409)."""


class DeviceLost(DeviceFault):
    """A device stopped answering (or is still gone when asked to recover); the message names it (HTTP 503)."""


class ShuttingDown(RefusedByCheck, ConnectionError):
    """The station is closing: no new command is accepted (HTTP 503)."""


class ArmMoving(CommandRefused):
    """A command that cannot take over the motion in progress (HTTP 409): a jog step sent while the arm still
    moves (the next step starts when this one has ended), or a motion that would not continue the running one
    (`reason` says why)."""

    def __init__(self, command: str, state: str, allowed: list[str] | tuple[str, ...], reason: str | None = None) -> None:
        super().__init__(command, state, allowed)
        self.reason = reason
        if reason is None:
            self.args = (f"command '{command}' refused: the arm is still moving; send the next step once it has stopped (?wait=true waits)",)
        else:
            self.args = (f"command '{command}' refused while the arm moves: {reason}",)


class NoArmError(CommandRefused):
    """A command that needs the arm, on a station that has none (`armlab serve --arm none`: perception only;
    HTTP 409 `no_arm`). Nothing is planned and nothing moves."""

    def __init__(self, command: str, state: str = "idle", allowed: list[str] | tuple[str, ...] = ()) -> None:
        super().__init__(command, state, allowed)
        self.args = (f"'{command}' refused: this station has no arm (perception only: calibrate, detections, click → world); "
                     "start it with an arm to move",)



class PlanNotFound(RefusedByCheck):
    """A motion plan id the station does not know (never made, discarded, or pushed out by newer plans): HTTP 404."""


class PlanStale(RefusedByCheck):
    """A motion plan that may no longer be executed (HTTP 409 `stale_plan`): it was executed already, expired, or the
    arm or its world changed since it was made. `reason` is the short word (executed, expired, arm_moved,
    arm_commanded, halted, scene_changed, calibration_changed, gripper_changed, speed_changed, arm_moving, job_changed); the
    message says what changed. Nothing moved: plan again."""

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason


class PlanNotYours(RefusedByCheck):
    """A motion plan made by another controller (HTTP 409 `not_controller`): each controller executes only the plans it
    made (the operator who saw the plan). Nothing moved."""


# What a planner raises when it declines a target (a job catches these and tries another move; anything
# else, a bare ValueError from a numpy bug included, fails the job as an internal error).
PLAN_REFUSALS: tuple[type[ArmlabError], ...] = (InvalidInput, Unreachable, PlanRefused)

# Built-in exceptions that, outside the hierarchy above, mean a bug (numpy's shape errors, a missing key).
BUG_TYPES: tuple[type[Exception], ...] = (ValueError, TypeError, LookupError, AttributeError, ArithmeticError, AssertionError, NameError)


def is_internal(error: BaseException) -> bool:
    """True for an exception that reports a bug rather than a refusal or a fault: a bare ValueError, TypeError,
    KeyError... that no ArmlabError subclass wraps."""
    return isinstance(error, BUG_TYPES) and not isinstance(error, ArmlabError)
