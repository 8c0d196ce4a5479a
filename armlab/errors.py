"""The few shared error types of the library; the server maps them to HTTP in one place."""

from __future__ import annotations


class DeviceNotConnectedError(ConnectionError):
    """A device method was called before connect() (or after close())."""

    def __init__(self, message: str = "device is not connected: call connect() first") -> None:
        super().__init__(message)


class DeviceAlreadyConnectedError(ConnectionError):
    """connect() was called on a device that is already connected."""

    def __init__(self, message: str = "device is already connected: call close() before connecting again") -> None:
        super().__init__(message)


class ConfigError(ValueError):
    """A configuration file or field is invalid; the message names the file and the field."""


class CommandRefused(RuntimeError):
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


class NotController(RuntimeError):
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


class CalibrationUntrusted(RuntimeError):
    """A grab, drop or autonomous job refused because the camera-moved check no longer confirms the
    calibration in use (HTTP 409 'not_calibrated'); the message gives the reason. Recalibrate, or let
    the board tags confirm the camera again."""


class NeedsConfirmation(RuntimeError):
    """A command that is dangerous in the current state and was sent without confirm: true (HTTP 409)."""


class DeviceLost(ConnectionError):
    """A device stopped answering (or is still gone when asked to recover); the message names it (HTTP 503)."""


class ShuttingDown(ConnectionError):
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
