"""The Arm interface: joint-space position control of a serial arm.

Units: radians, rad/s, seconds. Joint order is the arm config's `joint_names`. Every backend (the
MuJoCo simulation, the Interbotix arm) implements this; the station is its only caller.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class JointState:
    """Measured joint state. position_rad, velocity_rad_s: shape (dof,); timestamp_s: time.time()."""

    position_rad: np.ndarray
    velocity_rad_s: np.ndarray
    timestamp_s: float


@dataclass(frozen=True)
class JointTrajectory:
    """A time-stamped joint path the arm tracks, linearly interpolated between samples.

    times_s: shape (N,), strictly increasing, starting at 0. positions_rad: shape (N, dof).
    Planners (armlab.motion) sample it densely (≥ 100 Hz) so linear interpolation is exact enough.
    """

    times_s: np.ndarray
    positions_rad: np.ndarray

    def __post_init__(self) -> None:
        times = np.asarray(self.times_s, dtype=float)
        positions = np.asarray(self.positions_rad, dtype=float)
        if times.ndim != 1 or positions.ndim != 2 or positions.shape[0] != times.shape[0] or times.size == 0:
            raise ValueError(
                f"JointTrajectory: times_s must be (N,) and positions_rad (N, dof); got {times.shape} and {positions.shape}"
            )
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(positions))):
            raise ValueError("JointTrajectory: times_s and positions_rad must be finite")
        if times[0] != 0.0 or np.any(np.diff(times) <= 0.0):
            raise ValueError("JointTrajectory: times_s must start at 0 and be strictly increasing")
        object.__setattr__(self, "times_s", times)
        object.__setattr__(self, "positions_rad", positions)

    @property
    def duration_s(self) -> float:
        return float(self.times_s[-1])

    def sample(self, t_s: float) -> np.ndarray:
        """Joint positions at time t_s (clamped to the ends), by linear interpolation."""
        return np.array([np.interp(t_s, self.times_s, column) for column in self.positions_rad.T])


class Arm(abc.ABC):
    """A position-controlled arm.

    Blocking and errors: methods other than connect() raise DeviceNotConnectedError before connect();
    connect() raises DeviceAlreadyConnectedError when called twice and cleans up after a failure.
    """

    joint_names: tuple[str, ...]

    @abc.abstractmethod
    def connect(self) -> None:
        """Open the device; torque on, holding the current position."""

    @abc.abstractmethod
    def close(self) -> None:
        """Stop motion and release the device. Safe to call twice."""

    @property
    @abc.abstractmethod
    def is_connected(self) -> bool: ...

    @abc.abstractmethod
    def read_joint_state(self) -> JointState:
        """The newest measured joint state; never blocks on motion."""

    @abc.abstractmethod
    def command_trajectory(self, trajectory: JointTrajectory, wait: bool = False, start_time_s: float | None = None) -> float:
        """Start tracking `trajectory` (replacing any running one); returns its start (clock_s() of its t = 0).

        start_time_s: when its t = 0 is, on this arm's clock (clock_s()); the arm tracks the sample at
        clock_s() - start_time_s, so a command that reaches it late continues the same curve rather than
        starting it late (a takeover planned to splice onto the running motion at a given moment). None: now
        (a motion from rest). The sample it starts at should equal the current position. With wait=True, block
        until it ends or stop() is called. Raises ValueError for a wrong dof or joints outside the limits
        (nothing moves).
        """

    def clock_s(self) -> float:
        """The arm's clock for start_time_s: monotonic wall time (a simulated arm: the simulation's time)."""
        import time

        return time.monotonic()

    @abc.abstractmethod
    def is_moving(self) -> bool:
        """True while a commanded trajectory is still being tracked."""

    def wait_until_done(self, timeout_s: float | None = None) -> bool:
        """Block until the current trajectory ends; False on timeout."""
        import time

        deadline = None if timeout_s is None else time.monotonic() + timeout_s
        while self.is_moving():
            if deadline is not None and time.monotonic() > deadline:
                return False
            time.sleep(0.005)
        return True

    @abc.abstractmethod
    def stop(self) -> None:
        """Halt now: drop the trajectory and hold the current measured position (within one control period)."""

    @abc.abstractmethod
    def set_torque(self, enabled: bool) -> None:
        """Torque on (hold position) or off (limp)."""
