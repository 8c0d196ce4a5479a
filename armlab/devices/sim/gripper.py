"""SimGripper: the Gripper interface over the two finger servos. The fingers close with a force capped
at the configured grasp effort; "holding" means something resists them: driven closed, they stopped short of
fully closed and short of where they are driven (fingers halted mid-stroke by stop() hold nothing). Like the
arm's, stop() never waits for the workcell's lock: when it is busy the next control tick applies it."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

from armlab.devices.gripper import Gripper, GripperState
from armlab.devices.sim.device import SimDevice

if TYPE_CHECKING:
    from armlab.devices.sim.workcell import SimWorkcell

MOTION_TIMEOUT_S = 2.0
HOLDING_MARGIN_M = 0.001  # stopped at least this far from fully closed = holding something
RESIST_MARGIN_M = 0.001  # ... and at least this far (per finger) short of their reference: something keeps them open


class SimGripper(SimDevice, Gripper):
    """The simulated parallel gripper; width_m is the span between the pad faces."""

    def __init__(self, cell: SimWorkcell, offset_min_m: float, offset_max_m: float, pad_thickness_m: float,
                 stop_speed_m_s: float, stop_time_s: float, open_preload_m: float) -> None:
        self._cell = cell
        self._offset_min_m = offset_min_m
        self._offset_max_m = offset_max_m
        self._pad_thickness_m = pad_thickness_m
        self._stop_speed_m_s = stop_speed_m_s
        self._stop_time_s = stop_time_s
        self._open_reference_m = offset_max_m + open_preload_m  # open: held against the stop (config/sim.yaml says why)
        self._command = "release"
        self._command_s = 0.0
        self._still_since_s: float | None = None
        self._held_since_command = False  # the gripper has read holding since its last command (a grasp)
        self._reference_m = self._open_reference_m  # where the fingers are driven (per-finger offset)
        self._stop_requested = threading.Event()

    def __str__(self) -> str:
        return "SimGripper(rx200)"

    @property
    def command(self) -> str:
        """The last command: 'grasp' or 'release'."""
        return self._command

    @property
    def min_width_m(self) -> float:
        return 2.0 * (self._offset_min_m - self._pad_thickness_m)

    @property
    def max_width_m(self) -> float:
        return 2.0 * (self._offset_max_m - self._pad_thickness_m)

    def _set_command(self, command: str, offset_m: float) -> None:
        with self._cell.lock:
            self._apply_stop()  # a stop requested before this command came first
            self._command = command
            self._command_s = self._cell.sim_time_s
            self._still_since_s = None
            self._held_since_command = False
            self._reference_m = offset_m
            self._cell.apply_finger_reference(offset_m)
            self._last_reading = self._measure()

    def grasp(self, wait: bool = True) -> None:
        self._require()
        self._set_command("grasp", self._offset_min_m)
        if wait:
            self._cell.wait_for(self._stopped, MOTION_TIMEOUT_S)

    def release(self, wait: bool = True) -> None:
        self._require()
        self._set_command("release", self._open_reference_m)
        if wait:
            self._cell.wait_for(
                lambda: self._stopped() or min(self._cell.finger_positions()) >= self._offset_max_m - 5e-4,
                MOTION_TIMEOUT_S,
            )

    def stop(self) -> None:
        """Hold the fingers where they are (at once if the workcell's lock is free, else at the next tick);
        closed on a block (holding, now or at any time since the grasp) they keep squeezing it: the reference stays
        inside the block, so the grip force holds (a reference set to where the pads touch it would let it fall,
        issue 21; the fingers jiggle for ~90 ms after an arm's halt and the holding reading drops meanwhile)."""
        self._require()
        self._stop_requested.set()
        if self._cell.lock.acquire(blocking=False):
            try:
                self._apply_stop()
            finally:
                self._cell.lock.release()

    def _apply_stop(self) -> None:
        """Under the lock: apply a latched stop()."""
        if not self._stop_requested.is_set():
            return
        self._stop_requested.clear()
        if self._held_since_command or self._measure().holding:
            return
        left, right = self._cell.finger_positions()
        at_stop = min(left, right) >= self._offset_max_m - 1e-4  # open on its stop: stays held against it
        self._reference_m = self._open_reference_m if at_stop else 0.5 * (left + right)
        self._cell.apply_finger_reference(self._reference_m)

    def _stopped(self) -> bool:
        """Both fingers slower than stop_speed for stop_time (call under the lock or from wait_for)."""
        return self._still_since_s is not None and self._cell.sim_time_s - self._still_since_s >= self._stop_time_s

    def read_state(self) -> GripperState:
        """Now, or while the physics holds the workcell's lock the state at its last control tick (never waits)."""
        self._require()
        return self._fresh_or_last(self._measure)

    def _measure(self) -> GripperState:
        """The gripper's state now (under the lock)."""
        left, right = self._cell.finger_positions()
        width = left + right - 2.0 * self._pad_thickness_m
        resisted = 0.5 * (left + right) - self._reference_m > RESIST_MARGIN_M  # driven closer than they are
        holding = self._command == "grasp" and self._stopped() and width > self.min_width_m + HOLDING_MARGIN_M and resisted
        return GripperState(width_m=width, command=self._command, holding=holding, timestamp_s=time.time())

    def control(self, sim_time_s: float) -> None:
        """Track whether the fingers have stopped (called by the workcell under its lock)."""
        self._apply_stop()
        speeds = self._cell.finger_velocities()
        if max(abs(v) for v in speeds) < self._stop_speed_m_s and sim_time_s - self._command_s >= self._stop_time_s / 2:
            if self._still_since_s is None:
                self._still_since_s = sim_time_s
        else:
            self._still_since_s = None
        self._last_reading = self._measure()
        self._held_since_command = self._held_since_command or self._last_reading.holding
